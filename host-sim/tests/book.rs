//! The book's examples, run: every `console` block of docs/src and of the README (a
//! `$ foxhunt ...` line and the output it gives, `...` and `[..]` for what is left out) is
//! executed by trycmd against this build's `foxhunt` and must print what the page shows, so
//! the docs cannot drift from the command. `text` blocks (long benchmarks, live lines) are
//! figures with their command, not run.

use std::path::Path;

#[test]
fn book_examples() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .canonicalize()
        .expect("the repository's root");
    // The examples' working directory: a scratch folder, so the files they write land there
    // and never in the repository, with the repository's serial-bridge/ and docs/ linked in,
    // so the bundled captures and the example files are where the book says they are.
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("book");
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir_all(&scratch).expect("the scratch folder");
    for linked in ["serial-bridge", "docs"] {
        std::os::unix::fs::symlink(root.join(linked), scratch.join(linked))
            .expect("linked into the scratch folder");
    }
    std::env::set_current_dir(&scratch).expect("into the scratch folder");

    trycmd::TestCases::new()
        .register_bin("foxhunt", Path::new(env!("CARGO_BIN_EXE_foxhunt")))
        .case(root.join("docs/src/**/*.md"))
        .case(root.join("README.md"))
        .run();
}
