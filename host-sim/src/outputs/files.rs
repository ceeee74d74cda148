//! Files a command writes: only where the user said, never onto one of its inputs.

use crate::inputs::files::identity;
use crate::outputs::terminal::note;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Where a command may write: never onto one of its inputs, and never over an existing file
/// the command line did not name unless `--force`.
#[derive(Debug, Default)]
pub struct Outputs {
    inputs: Vec<((u64, u64), PathBuf)>,
    force: bool,
}

impl Outputs {
    /// Outputs of a command reading `inputs`.
    pub fn new<'a>(inputs: impl IntoIterator<Item = &'a Path>, force: bool) -> Self {
        Self {
            inputs: inputs
                .into_iter()
                .filter_map(|p| identity(p).map(|id| (id, p.to_path_buf())))
                .collect(),
            force,
        }
    }

    /// Refuse `path` before any work is done: it is an input, or (when the command line did
    /// not name it) an existing file.
    pub fn check(&self, path: &Path, named: bool) -> Result<(), String> {
        if let Some(id) = identity(path)
            && let Some((_, input)) = self.inputs.iter().find(|(i, _)| *i == id)
        {
            return Err(format!(
                "refusing to write {}: it is the input {}",
                path.display(),
                input.display()
            ));
        }
        if !named && !self.force && path.exists() {
            return Err(format!(
                "refusing to overwrite {}, which the command line did not name (give --force)",
                path.display()
            ));
        }
        Ok(())
    }

    /// Write `bytes` to `path` after [`Outputs::check`]; say so on stderr.
    pub fn write(&self, path: &Path, bytes: &[u8], named: bool) -> Result<(), String> {
        self.check(path, named)?;
        let mut f =
            File::create(path).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        f.write_all(bytes)
            .and_then(|_| f.sync_data())
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        note(&format!("wrote {}", path.display()));
        Ok(())
    }
}
