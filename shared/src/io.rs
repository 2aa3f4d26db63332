//! File access shared by both programs: `-` for standard input and output, and atomic writes
//! (a temporary file in the destination's folder, renamed into place only when complete), so a
//! failed run never leaves a half-written output.

use std::io::{Read, Write};
use std::path::Path;

use crate::error::{Error, Result};

/// True when `path` means standard input or output.
pub fn is_stdio(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// The bytes of an input: a memory map of a regular file, or a buffer (standard input, pipes).
pub enum Input {
    /// A mapped file.
    Mapped(memmap2::Mmap),
    /// Bytes read into memory.
    Buffer(Vec<u8>),
}

impl std::ops::Deref for Input {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            Input::Mapped(m) => m,
            Input::Buffer(b) => b,
        }
    }
}

/// Opens an input for reading without copying it: regular files are memory-mapped (the big
/// meshes parse straight from the page cache), standard input (`-`) and other files are read.
pub fn map_input(path: &Path) -> Result<Input> {
    if is_stdio(path) {
        return read_input(path).map(Input::Buffer);
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let meta = file.metadata().map_err(|e| Error::io(path, e))?;
    if meta.is_file() && meta.len() > 0 {
        // SAFETY: the map is read-only and private to this process; like any reader, we assume
        // the input is not truncated by another program while we parse it.
        if let Ok(m) = unsafe { memmap2::Mmap::map(&file) } {
            return Ok(Input::Mapped(m));
        }
    }
    read_input(path).map(Input::Buffer)
}

/// Reads a whole file, or standard input for `-`.
pub fn read_input(path: &Path) -> Result<Vec<u8>> {
    if is_stdio(path) {
        let mut buf = Vec::new();
        std::io::stdin()
            .lock()
            .read_to_end(&mut buf)
            .map_err(|e| Error::io(Path::new("<stdin>"), e))?;
        Ok(buf)
    } else {
        std::fs::read(path).map_err(|e| Error::io(path, e))
    }
}

/// The most bytes a parameter file (a TOML scene, an Anura3D CPS, a tolerance file) may hold:
/// thousands of times any real one, so that a device or a stream without end (`/dev/zero`, a
/// pipe that never closes with data) is refused at once instead of read until memory runs out.
pub const PARAMETER_FILE_LIMIT: u64 = 64 << 20;

/// Reads a parameter file, or standard input for `-`, of at most [`PARAMETER_FILE_LIMIT`] bytes;
/// a longer input is refused naming the file and the limit (meshes, which may be of any size,
/// are read with [`read_input`] or [`map_input`]).
pub fn read_parameters(path: &Path) -> Result<Vec<u8>> {
    read_at_most(path, PARAMETER_FILE_LIMIT)
}

/// [`read_parameters`] of a text file (a TOML scene, a tolerance file); bytes that are not
/// UTF-8 are refused as such.
pub fn read_parameter_text(path: &Path) -> Result<String> {
    String::from_utf8(read_parameters(path)?)
        .map_err(|_| Error::io(shown(path), std::io::Error::other("not UTF-8 text")))
}

/// The name messages give `path`: `<stdin>` for `-`.
fn shown(path: &Path) -> &Path {
    if is_stdio(path) {
        Path::new("<stdin>")
    } else {
        path
    }
}

/// [`read_parameters`] with the limit given.
fn read_at_most(path: &Path, limit: u64) -> Result<Vec<u8>> {
    let mut buf = Vec::new();
    let read = if is_stdio(path) {
        std::io::stdin()
            .lock()
            .take(limit + 1)
            .read_to_end(&mut buf)
    } else {
        let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        file.take(limit + 1).read_to_end(&mut buf)
    };
    let shown = shown(path);
    read.map_err(|e| Error::io(shown, e))?;
    if buf.len() as u64 > limit {
        let why = format!(
            "longer than {} MiB, more than any parameter file holds (a device or an endless \
             stream?)",
            limit >> 20
        );
        return Err(Error::io(shown, std::io::Error::other(why)));
    }
    Ok(buf)
}

/// Writes `bytes` to `path` atomically, or to standard output for `-`.
pub fn write_output(path: &Path, bytes: &[u8]) -> Result<()> {
    write_output_with(path, |w| w.write_all(bytes))
}

/// Calls `fill` with a writer for `path` (standard output for `-`); for a file, the data goes to a
/// temporary file beside it that replaces `path` only after `fill` succeeded and the data is
/// flushed. A symbolic link is written through (its target is replaced, the link stays), and a
/// device, FIFO or socket is written in place, as a shell's `>` would: renaming a file over
/// `/dev/null` would replace the device itself.
pub fn write_output_with<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    if is_stdio(path) {
        let stdout = std::io::stdout();
        let mut lock = stdout.lock();
        fill(&mut lock).map_err(|e| Error::io(Path::new("<stdout>"), e))?;
        return lock
            .flush()
            .map_err(|e| Error::io(Path::new("<stdout>"), e));
    }
    let shown = path;
    let target = through_links(path);
    let path = target.as_path();
    if let Ok(meta) = std::fs::metadata(path) {
        if !meta.is_file() && !meta.is_dir() {
            let file = std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(|e| Error::io(shown, e))?;
            let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
            fill(&mut w).map_err(|e| Error::io(shown, e))?;
            return w.flush().map_err(|e| Error::io(shown, e));
        }
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".tmp-")
        .tempfile_in(dir)
        .map_err(|e| Error::io(path, e))?;
    {
        let mut w = std::io::BufWriter::with_capacity(1 << 20, tmp.as_file_mut());
        fill(&mut w).map_err(|e| Error::io(path, e))?;
        w.flush().map_err(|e| Error::io(path, e))?;
    }
    // Temporary files are created private; give the result the usual mode of a new file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let perm = std::fs::Permissions::from_mode(0o644);
        std::fs::set_permissions(tmp.path(), perm).map_err(|e| Error::io(path, e))?;
    }
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// `path` with its symbolic links followed (up to 40, as the kernel allows), to the name the
/// last one points at whether or not that exists yet; `path` itself when it is not a link.
fn through_links(path: &Path) -> std::path::PathBuf {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        // (`read_link` fails on anything that is not a link, or does not exist.)
        let Ok(to) = std::fs::read_link(&p) else {
            break;
        };
        p = match p.parent() {
            Some(dir) if to.is_relative() => dir.join(to),
            _ => to,
        };
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        let r = write_output_with(&p, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert!(!p.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        write_output(&p, b"whole").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"whole");
    }

    #[cfg(unix)]
    #[test]
    fn links_are_written_through_and_devices_in_place() {
        let dir = tempfile::tempdir().unwrap();
        let (real, link) = (dir.path().join("real.txt"), dir.path().join("link.txt"));
        std::fs::write(&real, b"old").unwrap();
        std::os::unix::fs::symlink("real.txt", &link).unwrap();
        write_output(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        // A link whose target does not exist yet: the target is made, the link kept.
        let (later, dangling) = (dir.path().join("later.txt"), dir.path().join("d.txt"));
        std::os::unix::fs::symlink(&later, &dangling).unwrap();
        write_output(&dangling, b"made").unwrap();
        assert_eq!(std::fs::read(&later).unwrap(), b"made");
        assert!(std::fs::symlink_metadata(&dangling)
            .unwrap()
            .file_type()
            .is_symlink());
        // A failed write through a link leaves the target as it was.
        assert!(write_output_with(&link, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("boom"))
        })
        .is_err());
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        // A device stays a device (as root, a rename would have replaced it).
        write_output(Path::new("/dev/null"), b"gone").unwrap();
        let meta = std::fs::metadata("/dev/null").unwrap();
        assert!(!meta.is_file());
        // A full device is an error naming the path given.
        if Path::new("/dev/full").exists() {
            let e = write_output(Path::new("/dev/full"), b"x").unwrap_err();
            assert!(e.to_string().contains("/dev/full"), "{e}");
        }
        // Only temporary files of our own were made, and none is left.
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert!(names.iter().all(|n| !n.starts_with(".tmp-")), "{names:?}");
    }

    #[test]
    fn a_parameter_file_past_the_limit_is_refused_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("scene.toml");
        std::fs::write(&p, b"0123456789").unwrap();
        assert_eq!(read_at_most(&p, 10).unwrap(), b"0123456789");
        let e = read_at_most(&p, 9).unwrap_err().to_string();
        assert!(e.contains("scene.toml") && e.contains("longer than"), "{e}");
        // A device without end is refused, not read until memory runs out.
        #[cfg(unix)]
        {
            let e = read_at_most(Path::new("/dev/zero"), 1 << 20)
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("/dev/zero") && e.contains("longer than 1 MiB"),
                "{e}"
            );
        }
        let e = read_at_most(&dir.path().join("none.toml"), 9).unwrap_err();
        assert!(e.to_string().contains("none.toml"), "{e}");
        // Text that is not UTF-8: refused as such, the reason apart from the name.
        std::fs::write(&p, [b'a', 0xff, 0xfe]).unwrap();
        let e = read_parameter_text(&p).unwrap_err();
        assert!(e.to_string().contains("scene.toml"), "{e}");
        assert_eq!(e.reason(), "not UTF-8 text");
        std::fs::write(&p, "x = 1\n").unwrap();
        assert_eq!(read_parameter_text(&p).unwrap(), "x = 1\n");
    }
}
