//! Reading a bot's pipes safely: reply lines with a length cap, and a bounded stderr tail.

use std::collections::VecDeque;

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

/// Reads a bot's stderr to its end: keeps its last `cap` bytes (as [`read_tail`] does)
/// and hands each complete line, cut to [`STDERR_LINE_BYTES`], to `lines`.
pub async fn read_stderr<R: AsyncRead + Unpin>(
    stream: R,
    cap: usize,
    lines: StderrLines,
) -> String {
    let mut partial: Vec<u8> = Vec::new();
    let mut sent = 0usize;
    let mut emit = |line: &[u8]| {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        let text = crate::protocol::excerpt(line, STDERR_LINE_BYTES);
        if lines.echo {
            eprintln!("  bot stderr | {text}");
        }
        if sent < STDERR_TRACE_BYTES {
            sent += text.len() + 1;
            let _ = lines.trace.send(text);
        }
    };
    let tail = read_tail_with(stream, cap, |chunk| {
        for &b in chunk {
            if b == b'\n' {
                emit(&partial);
                partial.clear();
            } else if partial.len() <= STDERR_LINE_BYTES {
                partial.push(b);
            }
        }
    })
    .await;
    if !partial.is_empty() {
        emit(&partial);
    }
    tail
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

/// Reads `stream` to its end, keeping only the last `cap` bytes. Returns the tail as
/// text (lossy UTF-8), prefixed with a note of how much was cut.
pub async fn read_tail<R: AsyncRead + Unpin>(stream: R, cap: usize) -> String {
    read_tail_with(stream, cap, |_| {}).await
}

async fn read_tail_with<R: AsyncRead + Unpin>(
    mut stream: R,
    cap: usize,
    mut each: impl FnMut(&[u8]),
) -> String {
    let mut tail: VecDeque<u8> = VecDeque::with_capacity(cap.min(8192));
    let mut total: u64 = 0;
    let mut buf = vec![0u8; 8192];
    loop {
        match stream.read(&mut buf).await {
            Ok(0) | Err(_) => break,
            Ok(n) => {
                total += n as u64;
                each(&buf[..n]);
                tail.extend(&buf[..n]);
                if tail.len() > cap {
                    let extra = tail.len() - cap;
                    tail.drain(..extra);
                }
            }
        }
    }
    let kept = tail.len() as u64;
    let text = String::from_utf8_lossy(tail.make_contiguous()).into_owned();
    if total > kept {
        format!(
            "[... {} earlier bytes of stderr not kept]\n{text}",
            total - kept
        )
    } else {
        text
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

    #[tokio::test]
    async fn stderr_lines_are_handed_on_one_by_one_and_cut() {
        let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel();
        let long = "y".repeat(STDERR_LINE_BYTES + 100);
        let data = format!("one\r\ntwo\n{long}\nlast without newline");
        let tail = read_stderr(
            data.as_bytes(),
            1000,
            StderrLines {
                trace: tx,
                echo: false,
            },
        )
        .await;
        assert!(tail.ends_with("last without newline"));
        let mut got = Vec::new();
        while let Ok(l) = rx.try_recv() {
            got.push(l);
        }
        assert_eq!(got[..2], ["one", "two"]);
        assert!(got[2].ends_with('…') && got[2].len() < STDERR_LINE_BYTES + 10);
        assert_eq!(got[3], "last without newline");
    }

    #[tokio::test]
    async fn the_stderr_tail_is_bounded() {
        let data: Vec<u8> = (0..100_000u32).map(|i| b'a' + (i % 26) as u8).collect();
        let tail = read_tail(&data[..], 1000).await;
        assert!(tail.starts_with("[... 99000 earlier bytes"));
        assert!(tail.ends_with(std::str::from_utf8(&data[99_000..]).unwrap()));
        assert_eq!(read_tail(&b"short"[..], 1000).await, "short");
    }
}
