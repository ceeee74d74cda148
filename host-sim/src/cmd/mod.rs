//! The `foxhunt` subcommands: each one's options (clap) and the orchestration that reads its
//! inputs, calls the library and writes its outputs. `main.rs` only dispatches here.

pub mod bench;
pub mod frames;
pub mod locate;
pub mod perf;
pub mod serve;
pub mod simulate;
pub mod track;

use foxhunt_core::Method;

/// Parse a method name of the registry (clap value parser).
pub fn method(name: &str) -> Result<Method, String> {
    Method::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        format!("unknown method `{name}`; known: {}", names.join(", "))
    })
}
