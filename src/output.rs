//! Outputs that never destroy data: every file a command writes goes through here.
//!
//! Before anything runs, [`check_outputs`] refuses an output path that is one of the inputs,
//! two outputs on one path, and an existing output that is not a regular file (a device, a
//! directory, a link to either): only regular files are ever replaced. [`write_atomic`] writes
//! to a temporary name unique to this process and this write, syncs it and renames it over the
//! target; on every failure (a full disk, a vanished directory) the temporary file is removed
//! and the previous output stays as it was.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Why an output was refused or could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The path exists and is not a regular file (`what` it is instead).
    #[error("{} exists and is not a regular file ({what}): outputs only ever replace regular files", path.display())]
    NotRegular { path: PathBuf, what: &'static str },
    /// The output `what` is on the input `input`.
    #[error("{what} {} is the input {}: refusing to overwrite it", path.display(), input.display())]
    IsInput { what: String, path: PathBuf, input: PathBuf },
    /// The outputs `what` and `other` are on one path.
    #[error("{what} and {other} both write {}: give each its own path", path.display())]
    Shared { what: String, other: String, path: PathBuf },
    /// The output's folder could not be made or written (`why`).
    #[error("{} cannot be written: {} {why}", path.display(), dir.display())]
    NoFolder { path: PathBuf, dir: PathBuf, why: &'static str },
    /// The output's directory could not be made.
    #[error("cannot create {}: {source}", dir.display())]
    CreateDir { dir: PathBuf, source: std::io::Error },
    /// The output could not be written or renamed into place.
    #[error("cannot write {}: {source}", path.display())]
    Write { path: PathBuf, source: std::io::Error },
}

/// Counter that keeps the temporary names of one process apart.
static PARTIAL_SEQ: AtomicU64 = AtomicU64::new(0);

/// The temporary files being written now, so that an interrupted process removes them.
static IN_PROGRESS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary file still being written (an interrupted command calls this on its
/// way out: its outputs stay as they were before it started).
pub fn remove_partials() {
    if let Ok(mut list) = IN_PROGRESS.lock() {
        for p in list.drain(..) {
            let _ = std::fs::remove_file(p);
        }
    }
}

fn forget_partial(p: &Path) {
    if let Ok(mut list) = IN_PROGRESS.lock() {
        list.retain(|q| q != p);
    }
}

/// The path `p` stands for, for comparing paths: canonical where it exists, else its
/// directory's canonical path joined with its name (or the path made absolute).
pub fn identity(p: &Path) -> PathBuf {
    if let Ok(c) = std::fs::canonicalize(p) {
        return c;
    }
    let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    match (std::fs::canonicalize(dir), p.file_name()) {
        (Ok(d), Some(name)) => d.join(name),
        _ => std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf()),
    }
}

/// An error when `path` exists and is not a regular file (followed through links).
pub fn check_replaceable(path: &Path) -> Result<(), OutputError> {
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => Err(OutputError::NotRegular {
            path: path.to_path_buf(),
            what: if m.is_dir() { "a directory" } else { "a device, socket or pipe" },
        }),
        _ => Ok(()),
    }
}

/// The folder of an output can be made and written: its nearest existing ancestor is a
/// directory this process may write in (a missing folder is made when the output is written).
pub fn check_folder(path: &Path) -> Result<(), OutputError> {
    let here = Path::new(".");
    let existing =
        path.ancestors().skip(1).map(|d| if d.as_os_str().is_empty() { here } else { d }).find(|d| d.exists());
    let dir = existing.unwrap_or(here);
    let refused = |why| Err(OutputError::NoFolder { path: path.to_path_buf(), dir: dir.to_path_buf(), why });
    if !dir.is_dir() {
        return refused("is not a directory");
    }
    let Ok(c) = std::ffi::CString::new(dir.as_os_str().as_encoded_bytes()) else { return refused("is not a path") };
    // SAFETY: `c` is a NUL-terminated path that outlives the call; access only reads it.
    if unsafe { libc::access(c.as_ptr(), libc::W_OK) } != 0 {
        return refused("is not writable");
    }
    Ok(())
}

/// Refuses, before anything runs: an output equal to an input, two outputs on one path, an
/// output that exists but is not a regular file, and one whose folder cannot be made. `outputs` pairs each path with what it is
/// (`--json`, a recording of scenario X, ...), for the message.
pub fn check_outputs(inputs: &[PathBuf], outputs: &[(String, PathBuf)]) -> Result<(), OutputError> {
    let ins: Vec<PathBuf> = inputs.iter().map(|p| identity(p)).collect();
    let mut seen: Vec<(PathBuf, &str)> = Vec::new();
    for (what, path) in outputs {
        let id = identity(path);
        if let Some(k) = ins.iter().position(|i| *i == id) {
            return Err(OutputError::IsInput { what: what.clone(), path: path.clone(), input: inputs[k].clone() });
        }
        if let Some((_, other)) = seen.iter().find(|(p, _)| *p == id) {
            let (what, other) = (what.clone(), other.to_string());
            return Err(OutputError::Shared { what, other, path: path.clone() });
        }
        check_replaceable(path)?;
        check_folder(path)?;
        seen.push((id, what));
    }
    Ok(())
}

/// A temporary name beside `path`, unique to this process and this call:
/// `.NAME.PID.SEQ.partial.EXT` (hidden, so that a reader globbing the outputs skips it; the
/// extension kept for writers that choose the format by it). Registered until [`commit`] or
/// [`discard`], so that an interrupted process removes it ([`remove_partials`]).
pub fn partial_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_else(|| "output".into());
    let ext = path.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    let seq = PARTIAL_SEQ.fetch_add(1, Ordering::SeqCst);
    let p = path.with_file_name(format!(".{name}.{}.{seq}.partial{ext}", std::process::id()));
    if let Ok(mut list) = IN_PROGRESS.lock() {
        list.push(p.clone());
    }
    p
}

/// Removes the temporary file `partial` (a write that failed).
pub fn discard(partial: &Path) {
    let _ = std::fs::remove_file(partial);
    forget_partial(partial);
}

/// Renames the complete temporary file `partial` over `path` (a regular file or nothing);
/// removes `partial` when that fails.
pub fn commit(partial: &Path, path: &Path) -> Result<(), OutputError> {
    let done = check_replaceable(path).and_then(|()| {
        std::fs::rename(partial, path).map_err(|source| OutputError::Write { path: path.to_path_buf(), source })
    });
    if done.is_err() {
        let _ = std::fs::remove_file(partial);
    }
    forget_partial(partial);
    done
}

/// Writes `bytes` to `path` through a unique temporary file and a rename: never half-written,
/// never over anything but a regular file, and the previous file intact on any failure.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    check_replaceable(path)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        create_dir(dir)?;
    }
    let tmp = partial_path(path);
    let written = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })();
    if let Err(source) = written {
        discard(&tmp);
        return Err(OutputError::Write { path: path.to_path_buf(), source });
    }
    commit(&tmp, path)
}

/// Makes the directory `dir` (and its parents) for an output.
pub fn create_dir(dir: &Path) -> Result<(), OutputError> {
    std::fs::create_dir_all(dir).map_err(|source| OutputError::CreateDir { dir: dir.to_path_buf(), source })
}
