//! `--record FILE` of `monitor` and `hub`: the file checked before anything is opened,
//! created once there is something to record, and written a frame at a time.

use std::fs::File;
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use mcp_host::record::{Direction, RecordWriter};

use crate::Failure;

/// A recording's file, checked and not yet created: a recording is never lost to a
/// mistyped link, as the file is refused before the link is opened and made only once
/// the link is up.
#[derive(Debug)]
pub(crate) struct RecordingFile {
    path: PathBuf,
    force: bool,
}

impl RecordingFile {
    /// `path`, checked: not a directory; if there, a pipe, or overwritten only with
    /// `force` and only if it takes writes; if not, in a directory where a file can be
    /// made (a file is made there and removed): a session is never served unrecorded
    /// for want of the file.
    pub(crate) fn check(path: &Path, force: bool) -> Result<Self, Failure> {
        if path.is_dir() {
            return Err(Failure::input(format!(
                "{} is a directory: give a file to record to",
                path.display()
            )));
        }
        if is_fifo(path) {
            // A pipe (`--record >(gzip > f.gz)`, a FIFO): not opened here, as an open
            // would wait for a reader and a close end the reader's input; whether it has
            // a reader is seen when it is opened ([`create`](Self::create)).
        } else if path.exists() {
            if !force {
                return Err(exists(path));
            }
            // Overwritten with --force: it must take writes (opened without truncating).
            if let Err(e) = std::fs::OpenOptions::new().write(true).open(path) {
                return Err(Failure::input(format!(
                    "cannot record to {}: {e}",
                    path.display()
                )));
            }
        } else {
            let dir = match path.parent() {
                Some(dir) if !dir.as_os_str().is_empty() => dir,
                _ => Path::new("."),
            };
            let probe = dir.join(format!(".mcp-gs-record-check-{}", std::process::id()));
            match File::create_new(&probe) {
                Ok(_) => {
                    let _ = std::fs::remove_file(&probe);
                }
                Err(e) => {
                    return Err(Failure::input(format!(
                        "cannot record to {}: no file can be made in {}: {e}",
                        path.display(),
                        dir.display()
                    )));
                }
            }
        }
        Ok(RecordingFile {
            path: path.to_owned(),
            force,
        })
    }

    /// The file, created (truncated with `force`, else it must not exist); a pipe,
    /// opened if something reads it (a FIFO with no reader is refused, where its open
    /// would wait for one, deaf to Ctrl-C).
    pub(crate) fn create(&self) -> Result<Recording, Failure> {
        let path = &self.path;
        let file = if is_fifo(path) {
            open_pipe(path)
        } else if self.force {
            File::create(path)
        } else {
            File::create_new(path)
        };
        let file = file.map_err(|e| match e.kind() {
            io::ErrorKind::AlreadyExists => exists(path),
            _ => Failure::input(format!("cannot create {}: {e}", path.display())),
        })?;
        let writer = RecordWriter::new(BufWriter::new(file))
            .map_err(|e| Failure::input(format!("cannot write {}: {e}", path.display())))?;
        Ok(Recording {
            writer,
            path: path.clone(),
            frames: 0,
        })
    }
}

/// A recording being made.
pub(crate) struct Recording {
    writer: RecordWriter<BufWriter<File>>,
    path: PathBuf,
    /// Frames written so far.
    pub(crate) frames: u64,
}

impl Recording {
    /// Writes a frame, and flushes it to the file: what was recorded survives the
    /// program's end however it comes. The failure names the file.
    pub(crate) fn write(
        &mut self,
        time: SystemTime,
        direction: Direction,
        frame: &[u8],
    ) -> Result<(), Failure> {
        self.writer
            .write(time, direction, frame)
            .and_then(|()| self.writer.flush())
            .map_err(|e| {
                Failure::new(
                    Failure::OTHER,
                    format!("cannot write to {}: {e}", self.path.display()),
                )
            })?;
        self.frames += 1;
        Ok(())
    }

    /// The file's path.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }
}

/// The failure of a `--record` file that exists.
fn exists(path: &Path) -> Failure {
    Failure::input(format!(
        "{} exists: choose another file, or add --force to overwrite it",
        path.display()
    ))
}

/// Opens the pipe at `path` to write to it, if something reads it: a FIFO with no
/// reader is refused (an open would wait for one).
#[cfg(unix)]
fn open_pipe(path: &Path) -> io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    // Without waiting: ENXIO when nothing reads it.
    let probe = std::fs::OpenOptions::new()
        .write(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path);
    match probe {
        Err(e) if e.raw_os_error() == Some(libc::ENXIO) => Err(io::Error::new(
            io::ErrorKind::NotConnected,
            "it is a FIFO that nothing reads: start its reader first (`mcp-gs decode \
             FIFO`, say)",
        )),
        Err(e) => Err(e),
        // Something reads it: opened again to be written as a file is (blocking writes),
        // at once since a reader is there.
        Ok(_probe) => std::fs::OpenOptions::new().write(true).open(path),
    }
}

/// Opens the pipe at `path`: where there are no FIFOs, as a file.
#[cfg(not(unix))]
fn open_pipe(path: &Path) -> io::Result<File> {
    std::fs::OpenOptions::new().write(true).open(path)
}

/// Whether `path` is a FIFO (a named pipe).
#[cfg(unix)]
fn is_fifo(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| std::os::unix::fs::FileTypeExt::is_fifo(&m.file_type()))
}

/// Whether `path` is a FIFO: never, where there are none.
#[cfg(not(unix))]
fn is_fifo(_path: &Path) -> bool {
    false
}
