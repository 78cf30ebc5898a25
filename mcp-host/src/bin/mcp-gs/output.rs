//! Standard output written by a thread of its own, for a command that prints what its
//! link receives as it comes (`monitor`): a reader slower than the link (a pager, a
//! terminal paused, a pipe into a busy program) holds up that thread, never one of the
//! runtime's, so the link goes on reading meanwhile and counts what the command falls
//! behind on rather than stalling with it.

use std::io::{self, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use tokio::sync::{mpsc, oneshot};

/// Lines queued for the thread before [`Output::room`] waits.
const QUEUE: usize = 64;

/// Standard output, written by its own thread, line by line in the order given.
pub(crate) struct Output {
    lines: mpsc::Sender<String>,
    /// What the thread ended with, sent as it ends: awaited rather than joined, so that
    /// a wait given up (on a reader that takes nothing more) leaves nothing behind that
    /// the runtime would wait for as it shuts down.
    ended: oneshot::Receiver<io::Result<()>>,
    /// Lines the thread has written whole.
    written: Arc<AtomicU64>,
}

impl Output {
    /// Starts the thread.
    pub(crate) fn stdout() -> io::Result<Self> {
        let (lines, queued) = mpsc::channel(QUEUE);
        let (done, ended) = oneshot::channel();
        let written = Arc::new(AtomicU64::new(0));
        let counted = Arc::clone(&written);
        std::thread::Builder::new()
            .name("mcp-gs stdout".into())
            .spawn(move || {
                let _ = done.send(write_all(queued, &counted));
            })?;
        Ok(Output {
            lines,
            ended,
            written,
        })
    }

    /// How many lines the thread has written whole, as it goes on: a handle that
    /// outlives [`Output::finish`], to count those a wait for it given up left unwritten.
    pub(crate) fn written(&self) -> Arc<AtomicU64> {
        Arc::clone(&self.written)
    }

    /// Room for a line (given without its line end), once fewer than [`QUEUE`] are
    /// queued; `None` if the thread ended, on an error that [`Output::finish`] gives.
    /// Cancel-safe: a `select!` branch.
    pub(crate) async fn room(&self) -> Option<mpsc::Permit<'_, String>> {
        self.lines.reserve().await.ok()
    }

    /// Writes `lines` after those queued, and ends the thread: whether they could all
    /// be written. Cancel-safe in that dropping it leaves the thread to end by itself.
    pub(crate) async fn finish(self, lines: impl IntoIterator<Item = String>) -> io::Result<()> {
        for line in lines {
            match self.room().await {
                Some(room) => room.send(line),
                None => break,
            }
        }
        let Output { lines, ended, .. } = self;
        drop(lines);
        // The thread panicked (it does not: a bug) if it sent nothing.
        ended.await.unwrap_or_else(|_| {
            Err(io::Error::other(
                "the thread writing standard output failed",
            ))
        })
    }
}

/// The thread: each line as it comes, with those queued meanwhile in one write.
fn write_all(mut queued: mpsc::Receiver<String>, written: &AtomicU64) -> io::Result<()> {
    let mut batch = Vec::new();
    while let Some(line) = queued.blocking_recv() {
        batch.clear();
        batch.extend_from_slice(line.as_bytes());
        batch.push(b'\n');
        let mut lines = 1;
        while let Ok(line) = queued.try_recv() {
            batch.extend_from_slice(line.as_bytes());
            batch.push(b'\n');
            lines += 1;
        }
        // Locked for the batch alone: another line of the program (a summary) is not
        // held up for the life of the thread.
        let mut out = io::stdout().lock();
        out.write_all(&batch)?;
        out.flush()?;
        written.fetch_add(lines, Ordering::Relaxed);
    }
    Ok(())
}
