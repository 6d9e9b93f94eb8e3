//! Structures in from other tools' formats, written out as this testbed's scenario files
//! (`mechanism = "custom"`). `ntrt.rs`: NTRT's YAML model files; `yaml.rs`: YAML with line and
//! column; `draft.rs`: the plain structure an import makes and its TOML text.
//!
//! An import reads text and writes text: it builds and steps nothing. The written scenario is
//! then loaded like any other, so everything it says is validated again.

pub mod draft;
pub mod matrices;
pub mod ntrt;
pub mod self_stress;
pub mod yaml;

/// A rejected input, at a line and column of a file (both from 1; 0 for the file as a whole,
/// which is then written `file: message`).
#[derive(Debug, Clone, PartialEq)]
pub struct ImportError {
    pub file: String,
    pub line: usize,
    pub col: usize,
    pub message: String,
}

/// Largest input file an import reads \[bytes\] (as a scenario file: 16 MiB).
pub const MAX_IMPORT_BYTES: u64 = 16 << 20;

/// The text of an input file (a regular file, at most [`MAX_IMPORT_BYTES`]), or an error
/// naming it.
pub(crate) fn read_text(path: &std::path::Path) -> Result<String, ImportError> {
    crate::input::read_text(path, MAX_IMPORT_BYTES, false).map_err(|e| ImportError::whole(path, e.to_string()))
}

impl std::fmt::Display for ImportError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        if self.line == 0 {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}:{}:{}: {}", self.file, self.line, self.col, self.message)
        }
    }
}

impl std::error::Error for ImportError {}

impl ImportError {
    /// An error about the file `path` as a whole.
    pub fn whole(path: &std::path::Path, message: String) -> Self {
        ImportError { file: path.display().to_string(), line: 0, col: 0, message }
    }

    pub fn at(file: &str, at: yaml::At, message: impl Into<String>) -> Self {
        ImportError { file: file.into(), line: at.line, col: at.col, message: message.into() }
    }
}

/// What an import made: the scenario text, and everything of the source it left out (also
/// listed in the scenario's description).
#[derive(Debug, Clone)]
pub struct Imported {
    pub toml: String,
    pub skipped: Vec<String>,
    /// What the import chose where the source says nothing (its prestress), in sentences
    /// (also in the scenario's description).
    pub chosen: Vec<String>,
}

/// The least cable tension an import gives a structure whose source sets none \[N\].
pub const DEFAULT_LEAST_TENSION_N: f64 = 10.0;
