#!/usr/bin/env bash
# Run an ARM image on QEMU's netduinoplus2 (STM32F405) board; the timeout guards against an
# image that hangs (a wrong memory map locks the core up instead of exiting).
set -euo pipefail
exec timeout "${FOXHUNT_QEMU_TIMEOUT:-300}" qemu-system-arm -machine netduinoplus2 -nographic \
  -semihosting-config enable=on,target=native -kernel "$1"
