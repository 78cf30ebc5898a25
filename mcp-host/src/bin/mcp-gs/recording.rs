//! `--record FILE` of `monitor` and `hub`: the file checked before anything is opened,
//! created once there is something to record, and written a frame at a time by a
//! thread of its own.

use std::fs::File;
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, SystemTime};

use mcp_host::record::{Direction, RecordWriter};
use tokio::sync::{mpsc, oneshot};

use crate::Failure;

/// Frames queued for the thread that writes the file: a burst of a few seconds. When
/// the file takes them slower than they come for longer, the next are counted as
/// missed, not queued without bound.
const QUEUE: usize = 4096;

/// How long the frames still queued may take to be written once the command ends (less
/// than the few seconds Windows leaves a program once its console is closed).
const DRAIN: Duration = Duration::from_secs(3);

/// The most bytes written to the file at once: whole records of at most this many
/// bytes, which a pipe takes whole or not at all (`PIPE_BUF` on Linux), so that a
/// program ended while its reader waits leaves no record cut off in it.
const CHUNK: usize = 4096;

/// How long the last frames are written before the wait is said.
const SAID_AFTER: Duration = Duration::from_secs(1);

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
        let writer = RecordWriter::new(BufWriter::with_capacity(CHUNK, file))
            .map_err(|e| Failure::input(format!("cannot write {}: {e}", path.display())))?;
        Recording::start(writer, path.clone())
    }
}

/// A frame for the recording.
type Frame = (SystemTime, Direction, Vec<u8>);

/// A recording being made, written by a thread of its own: slow storage (a pipe whose
/// reader pauses, a network file system) holds up that thread, never the command's
/// loop, which goes on hearing Ctrl-C and serving its link.
pub(crate) struct Recording {
    frames: mpsc::Sender<Frame>,
    /// Frames the thread has written to the file and flushed.
    flushed: Arc<AtomicU64>,
    /// The thread's failed write, as it ends on one; nothing when it ends otherwise.
    /// Sent before the thread lets go of its queue, so it is there once the queue is
    /// seen closed.
    ended: oneshot::Receiver<Option<Failure>>,
    /// Whether the thread's end was seen, its failure taken.
    over: bool,
    path: PathBuf,
    /// Frames given to the thread.
    sent: u64,
    /// Frames that came while [`QUEUE`] frames waited for the file, not recorded.
    missed: u64,
}

/// How a recording ended.
pub(crate) struct Recorded {
    /// Frames written to the file (at least: the thread may be finishing a write as the
    /// wait for it ends).
    pub(crate) frames: u64,
    /// Frames not recorded: they came while the file was [`QUEUE`] frames behind, or
    /// were still to be written when it took no more in time at the end.
    pub(crate) missed: u64,
    /// The file's path.
    pub(crate) path: PathBuf,
    /// The write that failed, unless [`Recording::write`] or [`Recording::failed`] gave
    /// it already.
    pub(crate) failure: Option<Failure>,
}

impl Recording {
    /// Starts the thread that writes to `writer`.
    fn start(writer: RecordWriter<BufWriter<File>>, path: PathBuf) -> Result<Self, Failure> {
        let (frames, mut queued) = mpsc::channel(QUEUE);
        let (done, ended) = oneshot::channel();
        let flushed = Arc::new(AtomicU64::new(0));
        let (counted, named) = (flushed.clone(), path.clone());
        std::thread::Builder::new()
            .name("mcp-gs recording".into())
            .spawn(move || {
                let failure = write_all(writer, &mut queued, &counted).err().map(|e| {
                    Failure::new(
                        Failure::OTHER,
                        format!("cannot write to {}: {e}", named.display()),
                    )
                });
                let _ = done.send(failure);
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
            flushed,
            ended,
            over: false,
            path,
            sent: 0,
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
            Ok(()) => {
                self.sent += 1;
                Ok(())
            }
            Err(mpsc::error::TrySendError::Full(_)) => {
                self.missed += 1;
                Ok(())
            }
            Err(mpsc::error::TrySendError::Closed(_)) if self.over => Ok(()),
            Err(mpsc::error::TrySendError::Closed(_)) => {
                self.over = true;
                match self.ended.try_recv() {
                    Ok(failure) => failure.map_or(Ok(()), Err),
                    Err(_) => Err(failed_thread(&self.path)),
                }
            }
        }
    }

    /// A write's failure, as soon as the thread stopped on it (once); never otherwise.
    /// Cancel-safe: a `select!` branch.
    pub(crate) async fn failed(&mut self) -> Failure {
        if !self.over {
            // The thread ends before `end` only on a failed write.
            let failure = (&mut self.ended)
                .await
                .unwrap_or_else(|_| Some(failed_thread(&self.path)));
            self.over = true;
            if let Some(failure) = failure {
                return failure;
            }
        }
        std::future::pending().await
    }

    /// Ends the recording: the frames queued are written, for [`DRAIN`] at most (a
    /// pipe's reader that takes nothing more does not keep the command), or until
    /// Ctrl-C; said if it takes longer than a second.
    pub(crate) async fn end(self) -> Recorded {
        let Recording {
            frames,
            flushed,
            ended,
            over,
            path,
            sent,
            missed,
        } = self;
        drop(frames);
        let failure = match over {
            true => None,
            false => match Self::written(ended, &path).await {
                Some(Ok(failure)) => failure,
                Some(Err(_)) => Some(failed_thread(&path)),
                // Still writing: what it wrote is in the file, the rest is not.
                None => None,
            },
        };
        let frames = flushed.load(Ordering::Acquire);
        Recorded {
            frames,
            // What the thread was given and did not write, unless it stopped on a
            // failure (said as such).
            missed: match (&failure, over) {
                (None, false) => missed + sent.saturating_sub(frames),
                _ => missed,
            },
            path,
            failure,
        }
    }

    /// The thread's end, once it has written the frames queued: in [`DRAIN`] at most,
    /// said after [`SAID_AFTER`]; `None` if it had not by then, or Ctrl-C came.
    async fn written(
        ended: oneshot::Receiver<Option<Failure>>,
        path: &Path,
    ) -> Option<Result<Option<Failure>, oneshot::error::RecvError>> {
        // Listening at once: a Ctrl-C before the wait is said stops it too.
        let ctrl_c = crate::interrupt::ctrl_c();
        let said = async {
            tokio::time::sleep(SAID_AFTER).await;
            err!(
                "mcp-gs: writing the last frames to {} ({} at most; Ctrl-C stops now)",
                path.display(),
                mcp_host::render::Seconds(DRAIN)
            );
            std::future::pending::<()>().await;
        };
        tokio::select! {
            ended = tokio::time::timeout(DRAIN, ended) => ended.ok(),
            _ = ctrl_c => None,
            () = said => None,
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

/// The failure of `recording`'s file, as a write fails; never, without one. Cancel-safe:
/// a `select!` branch.
pub(crate) async fn write_failed(recording: &mut Option<Recording>) -> Failure {
    match recording {
        Some(recording) => recording.failed().await,
        None => std::future::pending().await,
    }
}

/// The failure of a thread that ended without saying how (it does not: a bug).
fn failed_thread(path: &Path) -> Failure {
    Failure::new(
        Failure::OTHER,
        format!("the thread writing {} failed", path.display()),
    )
}

/// The thread: writes each frame, in writes of whole records of at most [`CHUNK`]
/// bytes, and flushes them to the file as soon as no other is queued, so that what was
/// recorded survives the program's end however it comes; counts the frames flushed in
/// `flushed`. A write that fails part way (a full disk) leaves a file cut back to the
/// last whole record that reached it, which reads to its end without an error.
fn write_all(
    mut writer: RecordWriter<BufWriter<File>>,
    queued: &mut mpsc::Receiver<Frame>,
    flushed: &AtomicU64,
) -> io::Result<()> {
    let mut written = Written {
        whole: 0,
        header: mcp_host::record::HEADER_LEN as u64,
        unflushed: Vec::new(),
    };
    let result = write_records(&mut writer, queued, flushed, &mut written);
    if result.is_err() {
        // What the buffer still holds is dropped, not written on the way out (once the
        // file is cut back, a write at its old end would leave a hole).
        let (file, _unwritten) = writer.into_inner().into_parts();
        // A pipe's or a device's length is none to cut back to.
        let len = file
            .metadata()
            .ok()
            .filter(|m| m.is_file())
            .map(|m| m.len());
        if let Some(len) = len {
            // The records of the failed write that reached the file whole are kept, after
            // the header if that was whole (else nothing is: an empty file).
            let mut end = written.whole;
            if end + written.header <= len {
                end += written.header;
                for &record in &written.unflushed {
                    if end + record > len {
                        break;
                    }
                    end += record;
                    flushed.fetch_add(1, Ordering::Release);
                }
            }
            if len > end {
                let _ = file.set_len(end);
            }
        }
    }
    result
}

/// What the file holds: its length up to the last record flushed, and the lengths of
/// what was written since (in the buffer, or part way to the file): the header until
/// the first flush, and records.
struct Written {
    whole: u64,
    header: u64,
    unflushed: Vec<u64>,
}

/// [`write_all`]'s loop.
fn write_records(
    writer: &mut RecordWriter<BufWriter<File>>,
    queued: &mut mpsc::Receiver<Frame>,
    flushed: &AtomicU64,
    written: &mut Written,
) -> io::Result<()> {
    let flush = |writer: &mut RecordWriter<BufWriter<File>>, written: &mut Written| {
        writer.flush()?;
        let records = std::mem::take(&mut written.unflushed);
        flushed.fetch_add(records.len() as u64, Ordering::Release);
        written.whole += std::mem::take(&mut written.header) + records.iter().sum::<u64>();
        io::Result::Ok(())
    };
    while let Some((time, direction, frame)) = queued.blocking_recv() {
        let record = mcp_host::record::record_len(frame.len());
        if writer.get_ref().buffer().len() + record > CHUNK {
            flush(writer, written)?;
        }
        writer.write(time, direction, &frame)?;
        written.unflushed.push(record as u64);
        if queued.is_empty() {
            flush(writer, written)?;
        }
    }
    flush(writer, written)
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
