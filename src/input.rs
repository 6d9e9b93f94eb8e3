//! Inputs read within bounds: every file a command reads goes through [`read_text`]. Only a
//! regular file is opened (a FIFO would block the command, a device could never end) or
//! standard input where the command documents `-`; the limit is applied while reading, so an
//! endless input costs at most the limit and one byte.

use std::io::Read;
use std::path::Path;

/// The path that stands for standard input.
pub const STDIN: &str = "-";

/// Why an input could not be read (the caller adds where).
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file system refused.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// Not a regular file (`0` says what it is).
    #[error("cannot read: {0}, not a regular file")]
    NotRegular(&'static str),
    /// Longer than `limit` bytes.
    #[error("larger than an input of this kind may be: at most {limit} bytes")]
    TooLarge { limit: u64 },
    /// Not UTF-8 text.
    #[error("cannot read: not UTF-8 text ({0})")]
    NotUtf8(#[from] std::string::FromUtf8Error),
}

/// The text of `path` (standard input for [`STDIN`] when `stdin` allows it), at most `limit`
/// bytes; an error says why not, in words (the caller adds where).
pub fn read_text(path: &Path, limit: u64, stdin: bool) -> Result<String, ReadError> {
    let mut bytes = Vec::new();
    if stdin && path == Path::new(STDIN) {
        std::io::stdin().lock().take(limit + 1).read_to_end(&mut bytes)?;
    } else {
        let meta = std::fs::metadata(path)?;
        if !meta.is_file() {
            return Err(ReadError::NotRegular(if meta.is_dir() { "a directory" } else { "a pipe, socket or device" }));
        }
        std::fs::File::open(path).and_then(|f| f.take(limit + 1).read_to_end(&mut bytes))?;
    }
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge { limit });
    }
    Ok(String::from_utf8(bytes)?)
}
