//! Reading a bot's pipes safely: reply lines with a length cap, and a bounded stderr tail.

use std::collections::VecDeque;
use std::os::fd::AsFd;

use tokio::io::{AsyncRead, AsyncReadExt};
use tokio_util::codec::{AnyDelimiterCodec, FramedRead};

use crate::protocol::MAX_LINE_BYTES;

/// How much of a bot's stderr is kept: the last 64 KiB.
pub const STDERR_TAIL_BYTES: usize = 64 * 1024;

/// The most stderr bytes of a match that are also kept line by line in the trace (each
/// line with the step it was written during); the tail has the rest.
pub const STDERR_TRACE_BYTES: usize = 256 * 1024;

/// The most stderr lines one step of the trace keeps.
pub const STDERR_STEP_LINES: usize = 50;

/// A stderr line longer than this is cut (with "…") in the trace.
pub const STDERR_LINE_BYTES: usize = 500;

/// What the stderr reader does with each line besides keeping the tail.
#[derive(Debug)]
pub struct StderrLines {
    /// Where lines go for the trace, until [`STDERR_TRACE_BYTES`] have been sent.
    pub trace: tokio::sync::mpsc::UnboundedSender<String>,
    /// Print each line on our own stderr as it comes (`mazearena run --verbose`).
    pub echo: bool,
}

/// A request to the stderr reader: take in every stderr byte the bot has written so far,
/// then answer. The runner sends one after each answer so that the lines a bot wrote
/// before answering are handed on before the next step starts, however late the
/// reader's task would otherwise run.
pub type StderrSync = tokio::sync::oneshot::Sender<()>;

/// Reads a bot's stderr to its end: keeps its last `cap` bytes (with a note of how much was cut)
/// and hands each complete line, cut to [`STDERR_LINE_BYTES`], to `lines`. On each
/// request from `syncs` it first reads whatever the pipe already holds (without
/// waiting), so that the lines written before that moment have been handed on when it
/// answers.
pub async fn read_stderr<R: AsyncRead + AsFd + Unpin>(
    mut stream: R,
    cap: usize,
    lines: StderrLines,
    mut syncs: tokio::sync::mpsc::UnboundedReceiver<StderrSync>,
) -> String {
    let mut tail = Tail::new(cap);
    let mut splitter = LineSplitter::new(lines);
    let mut buf = vec![0u8; 8192];
    let mut syncs_open = true;
    loop {
        tokio::select! {
            biased;
            request = syncs.recv(), if syncs_open => match request {
                Some(answer) => {
                    let eof = read_ready(&stream, &mut buf, |chunk| {
                        tail.push(chunk);
                        splitter.push(chunk);
                    });
                    let _ = answer.send(());
                    if eof {
                        break;
                    }
                }
                None => syncs_open = false,
            },
            read = stream.read(&mut buf) => match read {
                Ok(0) | Err(_) => break,
                Ok(n) => {
                    tail.push(&buf[..n]);
                    splitter.push(&buf[..n]);
                }
            },
        }
    }
    splitter.finish();
    tail.into_text()
}

/// Whether `fd` holds bytes not yet read (or its end), right now.
pub fn has_unread_bytes(fd: &impl AsFd) -> bool {
    poll_readable(fd).unwrap_or(true)
}

/// Whether a read of `fd` would not wait now (bytes or the end); `None` if poll fails.
fn poll_readable(fd: &impl AsFd) -> Option<bool> {
    use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
    let mut fds = [PollFd::new(fd.as_fd(), PollFlags::POLLIN)];
    let n = poll(&mut fds, PollTimeout::ZERO).ok()?;
    Some(
        n > 0
            && fds[0]
                .revents()
                .is_some_and(|r| r.intersects(PollFlags::POLLIN | PollFlags::POLLHUP)),
    )
}

/// Reads what `fd` holds right now, without waiting, passing each chunk to `each`.
/// Returns whether the end of the stream was reached.
fn read_ready(fd: &impl AsFd, buf: &mut [u8], mut each: impl FnMut(&[u8])) -> bool {
    while poll_readable(fd) == Some(true) {
        match nix::unistd::read(fd.as_fd(), buf) {
            Ok(0) => return true,
            Ok(n) => each(&buf[..n]),
            Err(_) => return false,
        }
    }
    false
}

/// Cuts a byte stream into lines for [`StderrLines`].
struct LineSplitter {
    lines: StderrLines,
    partial: Vec<u8>,
    sent: usize,
}

impl LineSplitter {
    fn new(lines: StderrLines) -> Self {
        LineSplitter {
            lines,
            partial: Vec::new(),
            sent: 0,
        }
    }

    fn push(&mut self, chunk: &[u8]) {
        for &b in chunk {
            if b == b'\n' {
                self.emit();
            } else if self.partial.len() <= STDERR_LINE_BYTES {
                self.partial.push(b);
            }
        }
    }

    fn emit(&mut self) {
        let line = std::mem::take(&mut self.partial);
        let line = line.strip_suffix(b"\r").unwrap_or(&line);
        let text = crate::protocol::excerpt(line, STDERR_LINE_BYTES);
        if self.lines.echo {
            eprintln!("  bot stderr | {text}");
        }
        if self.sent < STDERR_TRACE_BYTES {
            self.sent += text.len() + 1;
            let _ = self.lines.trace.send(text);
        }
    }

    fn finish(mut self) {
        if !self.partial.is_empty() {
            self.emit();
        }
    }
}

/// A line reader over the bot's stdout that never buffers more than one capped line.
pub type ReplyReader<R> = FramedRead<R, AnyDelimiterCodec>;

/// Wraps a bot's stdout in a reader of "\n"-ended lines of at most
/// [`MAX_LINE_BYTES`] bytes.
pub fn reply_reader<R: AsyncRead>(stdout: R) -> ReplyReader<R> {
    FramedRead::new(
        stdout,
        AnyDelimiterCodec::new_with_max_length(b"\n".to_vec(), Vec::new(), MAX_LINE_BYTES),
    )
}

/// The last bytes of a stream, up to a cap, and how many came in all.
struct Tail {
    cap: usize,
    kept: VecDeque<u8>,
    total: u64,
}

impl Tail {
    fn new(cap: usize) -> Self {
        Tail {
            cap,
            kept: VecDeque::with_capacity(cap.min(8192)),
            total: 0,
        }
    }

    fn push(&mut self, chunk: &[u8]) {
        self.total += chunk.len() as u64;
        self.kept.extend(chunk);
        if self.kept.len() > self.cap {
            let extra = self.kept.len() - self.cap;
            self.kept.drain(..extra);
        }
    }

    /// The tail as text (lossy UTF-8), prefixed with a note of how much was cut.
    fn into_text(mut self) -> String {
        let kept = self.kept.len() as u64;
        let text = String::from_utf8_lossy(self.kept.make_contiguous()).into_owned();
        if self.total > kept {
            format!(
                "[... {} earlier bytes of stderr not kept]\n{text}",
                self.total - kept
            )
        } else {
            text
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use futures_util::StreamExt;

    #[tokio::test]
    async fn lines_split_across_reads_are_joined() {
        let (mut tx, rx) = tokio::io::duplex(16);
        let writer = tokio::spawn(async move {
            use tokio::io::AsyncWriteExt;
            for chunk in [
                &b"{\"rot"[..],
                b"ation\":0,",
                b"\"movement\":1}\n{\"reset\":true}\n",
            ] {
                tx.write_all(chunk).await.unwrap();
            }
        });
        let mut r = reply_reader(rx);
        assert_eq!(
            &r.next().await.unwrap().unwrap()[..],
            b"{\"rotation\":0,\"movement\":1}"
        );
        assert_eq!(&r.next().await.unwrap().unwrap()[..], b"{\"reset\":true}");
        writer.await.unwrap();
        assert!(r.next().await.is_none());
    }

    #[tokio::test]
    async fn a_10_mb_line_is_refused_without_buffering_it() {
        let (mut tx, rx) = tokio::io::duplex(64 * 1024);
        let writer = tokio::spawn(async move {
            use tokio::io::AsyncWriteExt;
            let chunk = vec![b'x'; 1024 * 1024];
            for _ in 0..10 {
                if tx.write_all(&chunk).await.is_err() {
                    return;
                }
            }
        });
        let mut r = reply_reader(rx);
        assert!(r.next().await.unwrap().is_err());
        assert!(r.read_buffer().len() <= 2 * MAX_LINE_BYTES + 64 * 1024);
        drop(r);
        writer.await.unwrap();
    }

    #[tokio::test]
    async fn a_line_of_exactly_64_kib_is_accepted() {
        let mut data = vec![b' '; MAX_LINE_BYTES];
        data.push(b'\n');
        let mut r = reply_reader(&data[..]);
        assert_eq!(r.next().await.unwrap().unwrap().len(), MAX_LINE_BYTES);
        let mut data = vec![b' '; MAX_LINE_BYTES + 1];
        data.push(b'\n');
        let mut r = reply_reader(&data[..]);
        assert!(r.next().await.unwrap().is_err());
    }

    fn lines_channel() -> (StderrLines, tokio::sync::mpsc::UnboundedReceiver<String>) {
        let (tx, rx) = tokio::sync::mpsc::unbounded_channel();
        let lines = StderrLines {
            trace: tx,
            echo: false,
        };
        (lines, rx)
    }

    fn received(rx: &mut tokio::sync::mpsc::UnboundedReceiver<String>) -> Vec<String> {
        let mut got = Vec::new();
        while let Ok(l) = rx.try_recv() {
            got.push(l);
        }
        got
    }

    #[tokio::test]
    async fn stderr_lines_are_handed_on_one_by_one_and_cut() {
        let (mut tx, rx) = tokio::net::unix::pipe::pipe().unwrap();
        let (lines, mut got) = lines_channel();
        let (_syncs, sync_rx) = tokio::sync::mpsc::unbounded_channel();
        let long = "y".repeat(STDERR_LINE_BYTES + 100);
        let data = format!("one\r\ntwo\n{long}\nlast without newline");
        tokio::io::AsyncWriteExt::write_all(&mut tx, data.as_bytes())
            .await
            .unwrap();
        drop(tx);
        let tail = read_stderr(rx, 1000, lines, sync_rx).await;
        assert!(tail.ends_with("last without newline"));
        let got = received(&mut got);
        assert_eq!(got[..2], ["one", "two"]);
        assert!(got[2].ends_with('…') && got[2].len() < STDERR_LINE_BYTES + 10);
        assert_eq!(got[3], "last without newline");
    }

    #[tokio::test]
    async fn a_sync_hands_on_every_line_already_written() {
        // The reader task is never polled between the write and the sync request on this
        // single-threaded runtime: only the sync's own read can find the lines.
        let (tx, rx) = tokio::net::unix::pipe::pipe().unwrap();
        let (lines, mut got) = lines_channel();
        let (syncs, sync_rx) = tokio::sync::mpsc::unbounded_channel();
        let reader = tokio::spawn(read_stderr(rx, 1000, lines, sync_rx));
        for step in 1..=50 {
            let text = format!("step {step}\n");
            assert_eq!(
                nix::unistd::write(&tx, text.as_bytes()).unwrap(),
                text.len()
            );
            let (answer, done) = tokio::sync::oneshot::channel();
            syncs.send(answer).unwrap();
            done.await.unwrap();
            assert_eq!(received(&mut got), [format!("step {step}")]);
        }
        drop(tx);
        assert!(reader.await.unwrap().ends_with("step 50\n"));
    }

    #[test]
    fn the_stderr_tail_is_bounded() {
        let data: Vec<u8> = (0..100_000u32).map(|i| b'a' + (i % 26) as u8).collect();
        let mut tail = Tail::new(1000);
        for chunk in data.chunks(777) {
            tail.push(chunk);
        }
        let text = tail.into_text();
        assert!(text.starts_with("[... 99000 earlier bytes"));
        assert!(text.ends_with(std::str::from_utf8(&data[99_000..]).unwrap()));
        let mut short = Tail::new(1000);
        short.push(b"short");
        assert_eq!(short.into_text(), "short");
    }
}
