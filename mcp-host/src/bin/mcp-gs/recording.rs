//! `--record FILE` of `monitor` and `hub`: the file checked before anything is opened,
//! created once there is something to record, and written a frame at a time by a
//! thread of its own.

use std::fs::File;
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

use mcp_host::record::{Direction, RecordWriter};
use tokio::sync::{mpsc, oneshot};

use crate::Failure;

/// Frames queued for the thread that writes the file: a burst of a few seconds. When
/// the file takes them slower than they come for longer, the next are counted as
/// missed, not queued without bound.
const QUEUE: usize = 4096;

/// How long the frames still queued may take to be written once the command ends.
const DRAIN: Duration = Duration::from_secs(5);

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
        Recording::start(writer, path.clone())
    }
}

/// A frame for the recording.
type Frame = (SystemTime, Direction, Vec<u8>);

/// What the thread writing a recording ended with.
struct Written {
    /// Frames written to the file.
    frames: u64,
    /// The write that failed, if one did (the thread stops there).
    failure: Option<Failure>,
}

/// A recording being made, written by a thread of its own: slow storage (a pipe whose
/// reader pauses, a network file system) holds up that thread, never the command's
/// loop, which goes on hearing Ctrl-C and serving its link.
pub(crate) struct Recording {
    frames: mpsc::Sender<Frame>,
    /// What the thread ended with. Sent before the thread lets go of its queue, so it
    /// is there once the queue is seen closed.
    ended: oneshot::Receiver<Written>,
    /// The thread's end, once [`write`](Self::write) found it (its failure taken).
    written: Option<Written>,
    path: PathBuf,
    /// Frames that came while [`QUEUE`] frames waited for the file, not recorded.
    missed: u64,
}

/// How a recording ended.
pub(crate) struct Recorded {
    /// Frames written to the file.
    pub(crate) frames: u64,
    /// Frames not recorded: they came while the file was [`QUEUE`] frames behind, or
    /// were still queued when it took no more in time at the end.
    pub(crate) missed: u64,
    /// The file's path.
    pub(crate) path: PathBuf,
    /// The write that failed, unless [`Recording::write`] gave it already.
    pub(crate) failure: Option<Failure>,
}

impl Recording {
    /// Starts the thread that writes to `writer`.
    fn start(writer: RecordWriter<BufWriter<File>>, path: PathBuf) -> Result<Self, Failure> {
        let (frames, mut queued) = mpsc::channel(QUEUE);
        let (done, ended) = oneshot::channel();
        let named = path.clone();
        std::thread::Builder::new()
            .name("mcp-gs recording".into())
            .spawn(move || {
                let _ = done.send(write_all(writer, &mut queued, &named));
                drop(queued);
            })
            .map_err(|e| {
                Failure::new(
                    Failure::OTHER,
                    format!("cannot start writing {}: {e}", path.display()),
                )
            })?;
        Ok(Recording {
            frames,
            ended,
            written: None,
            path,
            missed: 0,
        })
    }

    /// Queues a frame for the file; counts it as missed if the file is [`QUEUE`] frames
    /// behind. Once the thread stopped on a failed write: that failure, once (the
    /// recording is over; [`end`](Self::end) says what was written).
    pub(crate) fn write(
        &mut self,
        time: SystemTime,
        direction: Direction,
        frame: &[u8],
    ) -> Result<(), Failure> {
        match self.frames.try_send((time, direction, frame.to_vec())) {
            Ok(()) => Ok(()),
            Err(mpsc::error::TrySendError::Full(_)) => {
                self.missed += 1;
                Ok(())
            }
            Err(mpsc::error::TrySendError::Closed(_)) => {
                if self.written.is_none() {
                    self.written = Some(self.ended.try_recv().unwrap_or_else(|_| Written {
                        frames: 0,
                        failure: Some(failed_thread(&self.path)),
                    }));
                }
                let failure = self.written.as_mut().and_then(|w| w.failure.take());
                failure.map_or(Ok(()), Err)
            }
        }
    }

    /// A write's failure, as soon as the thread stopped on it (once); never otherwise.
    /// Cancel-safe: a `select!` branch.
    pub(crate) async fn failed(&mut self) -> Failure {
        if self.written.is_none() {
            // The thread ends before `end` only on a failed write.
            let written = (&mut self.ended).await.unwrap_or_else(|_| Written {
                frames: 0,
                failure: Some(failed_thread(&self.path)),
            });
            self.written = Some(written);
        }
        match self.written.as_mut().and_then(|w| w.failure.take()) {
            Some(failure) => failure,
            None => std::future::pending().await,
        }
    }

    /// Ends the recording: the frames queued are written, for [`DRAIN`] at most (a
    /// pipe's reader that takes nothing more does not keep the command).
    pub(crate) async fn end(self) -> Recorded {
        let Recording {
            frames,
            ended,
            written,
            path,
            mut missed,
        } = self;
        let queued = QUEUE - frames.capacity();
        drop(frames);
        let written = match written {
            Some(written) => written,
            None => match tokio::time::timeout(DRAIN, ended).await {
                Ok(Ok(written)) => written,
                Ok(Err(_)) => Written {
                    frames: 0,
                    failure: Some(failed_thread(&path)),
                },
                // Still writing: what it wrote is in the file, the rest is not.
                Err(_) => {
                    missed += queued as u64;
                    Written {
                        frames: 0,
                        failure: None,
                    }
                }
            },
        };
        Recorded {
            frames: written.frames,
            missed,
            path,
            failure: written.failure,
        }
    }
}

impl Recorded {
    /// Says the frames missed, if any, as a warning; the failure, if there was one.
    pub(crate) fn said(self) -> Result<(), Failure> {
        if self.missed > 0 {
            err!(
                "mcp-gs: warning: {} missing from the recording {}: writing the file fell \
                 behind",
                crate::counted(self.missed, "frame"),
                self.path.display()
            );
        }
        self.failure.map_or(Ok(()), Err)
    }
}

/// The failure of a thread that ended without saying how (it does not: a bug).
fn failed_thread(path: &Path) -> Failure {
    Failure::new(
        Failure::OTHER,
        format!("the thread writing {} failed", path.display()),
    )
}

/// The thread: writes each frame, and flushes it to the file as soon as no other is
/// queued, so that what was recorded survives the program's end however it comes.
fn write_all(
    mut writer: RecordWriter<BufWriter<File>>,
    queued: &mut mpsc::Receiver<Frame>,
    path: &Path,
) -> Written {
    // Frames in the file, and those written since the last flush.
    let (mut frames, mut unflushed) = (0u64, 0u64);
    let mut flush = |writer: &mut RecordWriter<_>, unflushed: &mut u64| {
        writer.flush()?;
        frames += std::mem::take(unflushed);
        io::Result::Ok(())
    };
    let mut result = Ok(());
    while let Some((time, direction, frame)) = queued.blocking_recv() {
        result = writer.write(time, direction, &frame);
        if result.is_err() {
            break;
        }
        unflushed += 1;
        if queued.is_empty() {
            result = flush(&mut writer, &mut unflushed);
            if result.is_err() {
                break;
            }
        }
    }
    let result = result.and_then(|()| flush(&mut writer, &mut unflushed));
    Written {
        frames,
        failure: result.err().map(|e| {
            Failure::new(
                Failure::OTHER,
                format!("cannot write to {}: {e}", path.display()),
            )
        }),
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
