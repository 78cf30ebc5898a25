//! Standard error written by a thread of its own, as standard output is for `monitor`
//! ([`crate::output`]): a reader that takes nothing (a pager paused on `2>&1 | less`, a
//! terminal stopped with Ctrl-S, a selection made in a Windows console) holds up that
//! thread, never the command, which goes on reading its link and recording. Lines that
//! find [`QUEUE`] lines waiting are dropped, and their number said before the next line
//! written (and at the end).

use std::io::{self, Write};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender, TrySendError};
use std::sync::{Arc, Mutex, OnceLock, PoisonError};
use std::time::Duration;

/// Lines waiting to be written before more are dropped.
const QUEUE: usize = 1024;

/// How long the end of the program waits for the lines queued to be written.
const FINISH_WAIT: Duration = Duration::from_secs(1);

/// The thread's queue and what it says when it ends; `None` once finished.
static THREAD: OnceLock<Mutex<Option<Thread>>> = OnceLock::new();

struct Thread {
    lines: SyncSender<Vec<u8>>,
    /// Lines dropped, not yet said.
    dropped: Arc<AtomicU64>,
    /// Ends (disconnects) as the thread does.
    ended: Receiver<()>,
}

/// Starts the thread: from now on [`write()`] queues lines for it. Without it (it could
/// not start), lines are written at once.
pub(crate) fn start() {
    let (lines, queued) = mpsc::sync_channel(QUEUE);
    let (done, ended) = mpsc::channel();
    let dropped = Arc::new(AtomicU64::new(0));
    let counted = Arc::clone(&dropped);
    let spawned = std::thread::Builder::new()
        .name("mcp-gs stderr".into())
        .spawn(move || {
            write_all(&queued, &counted, &mut io::stderr());
            drop(done);
        });
    if spawned.is_ok() {
        let thread = Thread {
            lines,
            dropped,
            ended,
        };
        let _ = THREAD.set(Mutex::new(Some(thread)));
        // A panic of the main thread, which ends the program, says its message after
        // the lines queued before it, which are not lost. (One of another thread, a
        // task's that the runtime catches, leaves the thread running.)
        let said = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if std::thread::current().name() == Some("main") {
                finish();
            }
            said(info);
        }));
    }
}

/// Writes `line` (with its line end) to standard error: queued for the thread if it
/// runs (dropped and counted if [`QUEUE`] lines wait), else at once, lost if standard
/// error cannot be written (the command's exit status says what happened).
pub(crate) fn write(line: Vec<u8>) {
    let thread = THREAD
        .get()
        .map(|thread| thread.lock().unwrap_or_else(PoisonError::into_inner));
    let line = match thread.as_deref() {
        Some(Some(thread)) => match thread.lines.try_send(line) {
            Ok(()) => return,
            Err(TrySendError::Full(_)) => {
                thread.dropped.fetch_add(1, Ordering::Relaxed);
                return;
            }
            Err(TrySendError::Disconnected(line)) => line,
        },
        _ => line,
    };
    drop(thread);
    let _ = io::stderr().lock().write_all(&line);
}

/// Ends the thread once it has written the lines queued, waiting [`FINISH_WAIT`] at
/// most (standard error may be read by nobody); lines written after it are written at
/// once. Called before the program exits.
pub(crate) fn finish() {
    let Some(thread) = THREAD.get() else { return };
    let Some(thread) = thread.lock().unwrap_or_else(PoisonError::into_inner).take() else {
        return;
    };
    let Thread { lines, ended, .. } = thread;
    drop(lines);
    let _ = ended.recv_timeout(FINISH_WAIT);
}

/// The thread: each line as it comes, with those queued meanwhile in one write, after
/// the number of those dropped, if any were; at the end, the number dropped since.
fn write_all(queued: &Receiver<Vec<u8>>, dropped: &AtomicU64, out: &mut impl Write) {
    let mut batch = Vec::new();
    let said_dropped = |batch: &mut Vec<u8>| {
        let n = dropped.swap(0, Ordering::Relaxed);
        if n > 0 {
            let _ = writeln!(
                batch,
                "mcp-gs: warning: {} of standard error dropped: it was not read as fast as \
                 they came",
                crate::counted(n, "line")
            );
        }
    };
    while let Ok(line) = queued.recv() {
        batch.clear();
        said_dropped(&mut batch);
        batch.extend_from_slice(&line);
        while let Ok(line) = queued.try_recv() {
            batch.extend_from_slice(&line);
        }
        let _ = out.write_all(&batch);
    }
    batch.clear();
    said_dropped(&mut batch);
    let _ = out.write_all(&batch);
}

/// A line of the logger, sent to [`write()`] as a whole once it is formatted.
pub(crate) struct LogLine(Vec<u8>);

impl Write for LogLine {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

impl Drop for LogLine {
    fn drop(&mut self) {
        if !self.0.is_empty() {
            write(std::mem::take(&mut self.0));
        }
    }
}

/// The logger's writer: a [`LogLine`] an event.
pub(crate) fn log_line() -> LogLine {
    LogLine(Vec::new())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A standard error that takes every line, and while it takes the first, finds one
    /// more dropped: as when lines come while the thread is held up.
    struct Slow<'a> {
        out: Vec<u8>,
        dropped: &'a AtomicU64,
    }

    impl Write for Slow<'_> {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.out.is_empty() {
                self.dropped.fetch_add(1, Ordering::Relaxed);
            }
            self.out.extend_from_slice(buf);
            Ok(buf.len())
        }

        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn lines_dropped_are_said_before_the_next_line_and_at_the_end() {
        let (lines, queued) = mpsc::sync_channel(QUEUE);
        let dropped = AtomicU64::new(2);
        lines.send(b"one\n".to_vec()).unwrap();
        lines.send(b"two\n".to_vec()).unwrap();
        drop(lines);
        let mut out = Slow {
            out: Vec::new(),
            dropped: &dropped,
        };
        write_all(&queued, &dropped, &mut out);
        let said = " of standard error dropped: it was not read as fast as they came";
        assert_eq!(
            String::from_utf8(out.out).unwrap(),
            format!("mcp-gs: warning: 2 lines{said}\none\ntwo\nmcp-gs: warning: 1 line{said}\n")
        );
    }
}
