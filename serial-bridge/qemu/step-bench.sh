# Sourced by steps.sh and hotspots.sh (from the workspace root): builds the step-bench image
# and a plugin, and runs one filter on the emulated Cortex-M4F.
out=target/footprint
mkdir -p "$out"
elf="$out/steps/thumbv7em-none-eabihf/firmware/foxhunt-step-bench"

# build_step_bench <plugin name>: compiles serial-bridge/qemu/<name>.c to $out/lib<name>.so and
# the image (N = 100) for thumbv7em-none-eabihf, firmware profile.
build_step_bench() {
  gcc -O2 -shared -fPIC -o "$out/lib$1.so" "serial-bridge/qemu/$1.c"
  CARGO_TARGET_DIR="$out/steps" cargo build -q --profile firmware -p foxhunt-bridge \
    --bin foxhunt-step-bench --target thumbv7em-none-eabihf
}

# run_step_bench <filter> <steps> <plugin spec>: the image's run; QEMU's stderr (where
# icount.c prints) goes to stdout, the image's own output is dropped.
run_step_bench() {
  timeout 600 qemu-system-arm -machine netduinoplus2 -nographic \
    -semihosting-config "enable=on,target=native,arg=step-bench,arg=$1,arg=$2" \
    -plugin "$3" -kernel "$elf" 2>&1 >/dev/null
}
