//! Atomic, checked outputs (docs/robustness.md): a file is written to a temporary file in its
//! own directory and renamed over its path only when complete and flushed to disk, so a failing
//! write — a full disk, an encoder error, a killed process — leaves whatever was at the path
//! before unchanged and no partial file behind; [`check_outputs`] rejects output paths that
//! cannot work before any work is done.

use std::cell::RefCell;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The directory `path` lives in (`.` for a bare file name).
fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// A fresh temporary path next to `path`: `.<name>.hfgi-<pid>-<n>.tmp`.
fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    parent_of(path).join(format!(".{name}.hfgi-{}-{n}.tmp", std::process::id()))
}

/// Writes `bytes` to `path` atomically (see the module docs).
///
/// Errors: [`Error::Io`] naming `path` (or the temporary file) when the directory is not
/// writable, the disk is full or the rename fails; `path` is then unchanged.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_bytes_with(path, bytes, |f| f)
}

/// [`write_bytes`] through a writer made from the temporary file by `wrap` — the hook the tests
/// use to inject a failing disk.
pub fn write_bytes_with<W: Write>(path: &Path, bytes: &[u8], wrap: impl FnOnce(File) -> W) -> Result<()> {
    if path.is_dir() {
        return Err(Error::param("output path", path.display(), "a file path, not a directory"));
    }
    let tmp = temp_path(path);
    let file = OpenOptions::new().write(true).create_new(true).open(&tmp).map_err(|e| Error::io(&tmp, e))?;
    let written = (|| -> std::io::Result<()> {
        let mut w = wrap(file.try_clone()?);
        w.write_all(bytes)?;
        w.flush()?;
        drop(w);
        file.sync_all()
    })();
    drop(file);
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::io(path, e));
    }
    commit(tmp, path)
}

/// Renames a complete, synced temporary file over `path`, or stages it when inside
/// [`all_or_nothing`]. On failure the temporary file is removed.
fn commit(tmp: PathBuf, path: &Path) -> Result<()> {
    let staged = STAGED.with(|s| match s.borrow_mut().as_mut() {
        Some(list) => {
            list.push((tmp.clone(), path.to_path_buf()));
            true
        }
        None => false,
    });
    if staged {
        return Ok(());
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

/// An output written piece by piece (an animation's GIF, frame after frame) with the same
/// guarantee as [`write_bytes`]: the pieces go to a temporary file next to the target, and only
/// [`TempFile::commit`] — after a flush and a sync — renames it over the target (or stages it
/// inside [`all_or_nothing`]). Dropped without a commit (an error, a panic), the temporary file
/// is removed and the target is unchanged. Memory stays bounded by what the writer buffers.
pub struct TempFile {
    tmp: PathBuf,
    path: PathBuf,
    file: Option<File>,
}

impl TempFile {
    /// A new temporary file for `path` (an error if `path` is a directory or its folder cannot
    /// take a new file).
    pub fn create(path: &Path) -> Result<Self> {
        if path.is_dir() {
            return Err(Error::param("output path", path.display(), "a file path, not a directory"));
        }
        let tmp = temp_path(path);
        let file = OpenOptions::new().write(true).create_new(true).open(&tmp).map_err(|e| Error::io(&tmp, e))?;
        Ok(Self { tmp, path: path.to_path_buf(), file: Some(file) })
    }

    /// The target path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A handle to write the pieces through (the same open file).
    pub fn writer(&self) -> Result<File> {
        let file = self.file.as_ref().ok_or_else(|| Error::format(&self.path, "already committed"))?;
        file.try_clone().map_err(|e| Error::io(&self.tmp, e))
    }

    /// Syncs the file and renames it over the target (staged inside [`all_or_nothing`]). Every
    /// writer must have been flushed before.
    pub fn commit(mut self) -> Result<()> {
        // On a failing sync the file stays held, so Drop removes the temporary file.
        let file = self.file.as_ref().ok_or_else(|| Error::format(&self.path, "already committed"))?;
        file.sync_all().map_err(|e| Error::io(&self.path, e))?;
        self.file = None;
        let tmp = std::mem::take(&mut self.tmp);
        commit(tmp, &self.path)
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if self.file.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

thread_local! {
    /// Temporary files written inside [`all_or_nothing`] and their targets, in write order.
    static STAGED: RefCell<Option<Vec<(PathBuf, PathBuf)>>> = const { RefCell::new(None) };
}

/// Restores the enclosing scope's list and removes the temporary files of a scope that did not
/// commit (an error or a panic inside it).
struct Scope {
    outer: Option<Vec<(PathBuf, PathBuf)>>,
    committed: bool,
}

impl Drop for Scope {
    fn drop(&mut self) {
        let mine = STAGED.with(|s| std::mem::replace(&mut *s.borrow_mut(), self.outer.take()));
        if !self.committed {
            for (tmp, _) in mine.unwrap_or_default() {
                let _ = std::fs::remove_file(tmp);
            }
        }
    }
}

/// Runs `f` with every [`write_bytes`] inside it staged: the files are written to their
/// temporary paths and renamed into place together only if `f` succeeds, so a command with
/// several outputs changes all of them or none (if `f` fails or panics, the temporary files are
/// removed and every target is as before). Only a failing rename — after every file was written
/// and synced — can leave the earlier targets replaced and the later ones not. Scopes nest: an
/// inner scope's files commit with the outermost one. Per thread.
pub fn all_or_nothing<T, E: From<Error>>(f: impl FnOnce() -> std::result::Result<T, E>) -> std::result::Result<T, E> {
    let outer = STAGED.with(|s| s.borrow_mut().replace(Vec::new()));
    let nested = outer.is_some();
    let mut scope = Scope { outer, committed: false };
    let value = f()?;
    let mine = STAGED.with(|s| s.borrow_mut().take()).unwrap_or_default();
    if nested {
        scope.outer.get_or_insert_with(Vec::new).extend(mine);
        scope.committed = true;
        return Ok(value);
    }
    let mut failed = None;
    for (tmp, path) in mine {
        if failed.is_none() {
            if let Err(e) = std::fs::rename(&tmp, &path) {
                failed = Some(Error::io(&path, e));
            } else {
                continue;
            }
        }
        let _ = std::fs::remove_file(&tmp);
    }
    scope.committed = true;
    match failed {
        Some(e) => Err(e.into()),
        None => Ok(value),
    }
}

/// Checks output paths before any work: none is a directory, none names the same file as an
/// input or another output, and each one's directory exists (it is created if missing) and
/// accepts a new file. Inputs that do not exist are ignored.
///
/// Errors: [`Error::InvalidParameter`] naming the path and what is wrong, or [`Error::Io`] when
/// a directory cannot be created or written.
pub fn check_outputs(outputs: &[&Path], inputs: &[&Path]) -> Result<()> {
    let inputs: Vec<(&Path, PathBuf)> = inputs.iter().filter(|p| p.exists()).map(|p| (*p, identity(p))).collect();
    let mut seen: Vec<(&Path, PathBuf)> = Vec::new();
    for out in outputs {
        if out.is_dir() {
            return Err(Error::param("output path", out.display(), "a file path, not a directory"));
        }
        let id = identity(out);
        if let Some((input, _)) = inputs.iter().find(|(_, i)| *i == id) {
            return Err(Error::param(
                "output path",
                out.display(),
                format!("a file other than the input {} (it would be overwritten)", input.display()),
            ));
        }
        if let Some((other, _)) = seen.iter().find(|(_, i)| *i == id) {
            return Err(Error::param(
                "output path",
                out.display(),
                format!("a file other than the output {}", other.display()),
            ));
        }
        seen.push((out, id));
    }
    // Only now, with every path valid, create the missing folders and try each one.
    for out in outputs {
        let dir = parent_of(out);
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let probe = temp_path(out);
        OpenOptions::new().write(true).create_new(true).open(&probe).map_err(|e| Error::io(dir, e))?;
        let _ = std::fs::remove_file(&probe);
    }
    Ok(())
}

/// What `p` names, as far as the file system can tell: the canonical path, or for a file that
/// does not exist yet its folder's canonical path and its name.
fn identity(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    match (parent_of(p).canonicalize(), p.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => p.to_path_buf(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A disk that fills up after `left` bytes.
    struct FullAfter {
        inner: File,
        left: usize,
    }

    impl Write for FullAfter {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.left == 0 {
                return Err(std::io::Error::from_raw_os_error(28)); // ENOSPC
            }
            let n = buf.len().min(self.left);
            self.left -= n;
            self.inner.write(&buf[..n])
        }
        fn flush(&mut self) -> std::io::Result<()> {
            self.inner.flush()
        }
    }

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("hfgi-atomic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn a_full_disk_leaves_the_previous_file_and_no_temporary() {
        let d = dir("full");
        let p = d.join("out.png");
        std::fs::write(&p, b"previous content").unwrap();
        let err = write_bytes_with(&p, &[7u8; 4096], |f| FullAfter { inner: f, left: 100 }).unwrap_err();
        assert!(err.to_string().contains("out.png"), "{err}");
        assert_eq!(std::fs::read(&p).unwrap(), b"previous content");
        assert_eq!(entries(&d), ["out.png"]);
        // The same write without the fault replaces it whole.
        write_bytes(&p, &[7u8; 4096]).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), vec![7u8; 4096]);
        assert_eq!(entries(&d), ["out.png"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn several_outputs_change_together_or_not_at_all() {
        let d = dir("batch");
        let (a, b) = (d.join("a.png"), d.join("b.exr"));
        std::fs::write(&a, b"old a").unwrap();
        std::fs::write(&b, b"old b").unwrap();
        // The second output fails (a full disk): the first, already written, is not committed.
        let r: Result<()> = all_or_nothing(|| {
            write_bytes(&a, b"new a")?;
            write_bytes_with(&b, &[1u8; 64], |f| FullAfter { inner: f, left: 10 })
        });
        assert!(r.is_err());
        assert_eq!((std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap()), (b"old a".to_vec(), b"old b".to_vec()));
        assert_eq!(entries(&d), ["a.png", "b.exr"]);
        // Work that fails after the writes (not a write error) commits nothing either.
        let r: Result<()> = all_or_nothing(|| {
            write_bytes(&a, b"new a")?;
            Err(Error::param("late check", 1, "nothing"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read(&a).unwrap(), b"old a");
        assert_eq!(entries(&d), ["a.png", "b.exr"]);
        // Success commits both.
        all_or_nothing(|| -> Result<()> {
            write_bytes(&a, b"new a")?;
            write_bytes(&b, b"new b")
        })
        .unwrap();
        assert_eq!((std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap()), (b"new a".to_vec(), b"new b".to_vec()));
        assert_eq!(entries(&d), ["a.png", "b.exr"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn outputs_are_checked_before_work() {
        let d = dir("check");
        let scene = d.join("scene.toml");
        std::fs::write(&scene, "[gi]\n").unwrap();
        let e = check_outputs(&[&scene], &[&scene]).unwrap_err().to_string();
        assert!(e.contains("scene.toml") && e.contains("input"), "{e}");
        let e = check_outputs(&[&d], &[]).unwrap_err().to_string();
        assert!(e.contains("not a directory"), "{e}");
        let a = d.join("a.png");
        let e = check_outputs(&[&a, &d.join(".").join("a.png")], &[]).unwrap_err().to_string();
        assert!(e.contains("a.png"), "{e}");
        // A missing directory is created; nothing else is left behind.
        let deep = d.join("new/dir/x.exr");
        check_outputs(&[&deep], &[&scene]).unwrap();
        assert!(d.join("new/dir").is_dir());
        assert!(entries(&d.join("new/dir")).is_empty());
        assert_eq!(std::fs::read_to_string(&scene).unwrap(), "[gi]\n");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
