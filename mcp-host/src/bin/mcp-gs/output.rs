//! Standard output written by a thread of its own, for a command that prints what its
//! link receives as it comes (`monitor`): a reader slower than the link (a pager, a
//! terminal paused, a pipe into a busy program) holds up that thread, never one of the
//! runtime's, so the link goes on reading meanwhile and counts what the command falls
//! behind on rather than stalling with it.

use std::io::{self, Write};
use std::thread::JoinHandle;

use tokio::sync::mpsc;

/// Lines queued for the thread before [`Output::line`] waits for room.
const QUEUE: usize = 64;

/// Standard output, written by its own thread, line by line in the order given.
pub(crate) struct Output {
    lines: mpsc::Sender<String>,
    thread: JoinHandle<io::Result<()>>,
}

impl Output {
    /// Starts the thread.
    pub(crate) fn stdout() -> io::Result<Self> {
        let (lines, queued) = mpsc::channel(QUEUE);
        let thread = std::thread::Builder::new()
            .name("mcp-gs stdout".into())
            .spawn(move || write_all(queued))?;
        Ok(Output { lines, thread })
    }

    /// Room for a line (given without its line end), once fewer than [`QUEUE`] are
    /// queued; `None` if the thread ended, on an error that [`Output::finish`] gives.
    /// Cancel-safe: a `select!` branch.
    pub(crate) async fn room(&self) -> Option<mpsc::Permit<'_, String>> {
        self.lines.reserve().await.ok()
    }

    /// Writes `lines` after those queued, and ends the thread: whether they could all
    /// be written.
    pub(crate) async fn finish(self, lines: impl IntoIterator<Item = String>) -> io::Result<()> {
        for line in lines {
            match self.room().await {
                Some(room) => room.send(line),
                None => break,
            }
        }
        let Output { lines, thread } = self;
        drop(lines);
        match tokio::task::spawn_blocking(move || thread.join()).await {
            Ok(Ok(written)) => written,
            // The thread panicked (it does not: a bug), or the runtime is shutting down.
            _ => Err(io::Error::other(
                "the thread writing standard output failed",
            )),
        }
    }
}

/// The thread: each line as it comes, with those queued meanwhile in one write.
fn write_all(mut queued: mpsc::Receiver<String>) -> io::Result<()> {
    let mut batch = Vec::new();
    while let Some(line) = queued.blocking_recv() {
        batch.clear();
        batch.extend_from_slice(line.as_bytes());
        batch.push(b'\n');
        while let Ok(line) = queued.try_recv() {
            batch.extend_from_slice(line.as_bytes());
            batch.push(b'\n');
        }
        // Locked for the batch alone: another line of the program (a summary) is not
        // held up for the life of the thread.
        let mut out = io::stdout().lock();
        out.write_all(&batch)?;
        out.flush()?;
    }
    Ok(())
}
