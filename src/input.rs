//! Inputs read within bounds: every file a command reads goes through [`read_text`]. Only a
//! regular file is opened (a FIFO would block the command, a device could never end) or
//! standard input where the command documents `-`; the limit is applied while reading, so an
//! endless input costs at most the limit and one byte.

use std::io::Read;
use std::path::Path;

/// The path that stands for standard input.
pub const STDIN: &str = "-";

/// The text of `path` (standard input for [`STDIN`] when `stdin` allows it), at most `limit`
/// bytes; an error says why not, in words (the caller adds where).
pub fn read_text(path: &Path, limit: u64, stdin: bool) -> Result<String, String> {
    let mut bytes = Vec::new();
    let read = if stdin && path == Path::new(STDIN) {
        std::io::stdin().lock().take(limit + 1).read_to_end(&mut bytes)
    } else {
        let meta = std::fs::metadata(path).map_err(|e| format!("cannot read: {e}"))?;
        if !meta.is_file() {
            let what = if meta.is_dir() { "a directory" } else { "a pipe, socket or device" };
            return Err(format!("cannot read: {what}, not a regular file"));
        }
        std::fs::File::open(path).and_then(|f| f.take(limit + 1).read_to_end(&mut bytes))
    };
    read.map_err(|e| format!("cannot read: {e}"))?;
    if bytes.len() as u64 > limit {
        return Err(format!("larger than an input of this kind may be: at most {limit} bytes"));
    }
    String::from_utf8(bytes).map_err(|e| format!("cannot read: not UTF-8 text ({e})"))
}
