//! Reading a bot's pipes safely: reply lines with a length cap, and a bounded stderr tail.
//!
//! Both readers take bytes two ways: awaited through the runtime (a bot that thinks),
//! or by a read made at once on the pipe that `ppoll` just found ready (the match's
//! fast wait, [`super::session`]): the same buffers, so a line may come partly each way.

use std::os::fd::AsFd;

use tokio::io::{AsyncRead, AsyncReadExt};

use crate::protocol::MAX_LINE_BYTES;

/// How much of a bot's stderr is kept: the last 64 KiB.
pub const STDERR_TAIL_BYTES: usize = 64 * 1024;

/// The most stderr bytes of a match that are also kept line by line in the trace (each
/// line with the step it was written during); past them one line says so, and the
/// tail has the rest.
pub const STDERR_TRACE_BYTES: usize = 64 * 1024;

/// The line that ends a match's stderr lines in the trace once they reach
/// [`STDERR_TRACE_BYTES`].
pub const STDERR_TRACE_FULL: &str =
    "[mazearena: the match's stderr lines reached 64 KiB; later lines are only in the stderr tail]";

/// The most stderr lines one step of the trace keeps.
pub const STDERR_STEP_LINES: usize = 50;

/// A stderr line longer than this is cut (with "…") in the trace.
pub const STDERR_LINE_BYTES: usize = 500;

/// A bot's stderr, read by the match's own task while it waits for an answer: keeps
/// the last `cap` bytes (with a note of how much was cut) and cuts the rest into lines
/// (each cut to [`STDERR_LINE_BYTES`]) for the trace.
///
/// The stderr bytes a bot wrote before an answer are read before that answer: the
/// runner's wait polls [`StderrReader::read_some`] first, and the kernel reports the
/// stderr pipe ready no later than the stdout pipe written after it. So no step needs
/// a system call of its own to find them.
#[derive(Debug)]
pub struct StderrReader<R> {
    stream: R,
    open: bool,
    tail: Tail,
    splitter: LineSplitter,
    buf: Box<[u8]>,
    /// The step's output, for the charge of a flood ([`super::flood`]).
    pub meter: super::flood::FloodMeter,
}

/// How much one read of a bot's stderr takes at most: a whole pipe's worth, so that a
/// flood costs the referee one read for each of the bot's full writes.
const STDERR_READ_BYTES: usize = 64 * 1024;

impl<R: AsyncRead + Unpin> StderrReader<R> {
    /// Reads `stream`, keeping its last `cap` bytes; with `echo`, each line is also
    /// printed on our own stderr as it comes (`mazearena run --verbose`).
    pub fn new(stream: R, cap: usize, echo: bool) -> Self {
        StderrReader {
            stream,
            open: true,
            tail: Tail::new(cap),
            splitter: LineSplitter::new(echo),
            buf: vec![0u8; STDERR_READ_BYTES].into_boxed_slice(),
            meter: super::flood::FloodMeter::default(),
        }
    }

    /// Waits until the pipe holds bytes (or ends), then takes in one read of them.
    /// Cancel safe: dropped before it completes, it has read nothing.
    pub async fn read_some(&mut self) {
        let read = self.stream.read(&mut self.buf).await;
        self.take_in(read);
    }

    /// Waits for `event` while reading the stderr, taking in every stderr byte the
    /// pipe holds before `event` is looked at (up to `STDERR_READS_BEFORE_REPLY`
    /// reads in a row). Cancel safe when `event` is.
    pub async fn drain_while<F: std::future::Future>(&mut self, event: F) -> F::Output {
        use futures_util::FutureExt;
        tokio::pin!(event);
        let mut in_a_row = 0;
        loop {
            if in_a_row >= STDERR_READS_BEFORE_REPLY {
                in_a_row = 0;
                if let Some(out) = event.as_mut().now_or_never() {
                    return out;
                }
            }
            tokio::select! {
                biased;
                () = self.read_some(), if self.open => in_a_row += 1,
                out = event.as_mut() => return out,
            }
        }
    }

    /// The complete lines read since the last call (at most [`STDERR_TRACE_BYTES`] of
    /// them over the whole stream).
    pub fn take_lines(&mut self) -> Vec<String> {
        std::mem::take(&mut self.splitter.lines)
    }

    /// Reads the stream to its end, for at most `wait`; then the tail as text (noting
    /// when the end was not reached) and the lines not yet taken.
    pub async fn finish(mut self, wait: std::time::Duration) -> (String, Vec<String>) {
        let to_end = async {
            while self.open {
                self.read_some().await;
            }
        };
        let ended = tokio::time::timeout(wait, to_end).await.is_ok();
        if !ended {
            self.splitter.finish();
        }
        let mut tail = self.tail.into_text();
        if !ended {
            tail.push_str("\n[stderr could not be read to its end]");
        }
        (tail, self.splitter.lines)
    }
}

impl<R> StderrReader<R> {
    /// Whether the pipe may still hold bytes (its end was not read yet).
    pub fn is_open(&self) -> bool {
        self.open
    }

    fn take_in(&mut self, read: std::io::Result<usize>) {
        match read {
            Ok(0) | Err(_) => {
                self.open = false;
                self.splitter.finish();
            }
            Ok(n) => {
                self.meter.add(n as u64);
                self.tail.push(&self.buf[..n]);
                self.splitter.push(&self.buf[..n]);
            }
        }
    }
}

impl<R: AsFd> StderrReader<R> {
    /// The pipe, for a wait on it.
    pub fn pipe(&self) -> std::os::fd::BorrowedFd<'_> {
        self.stream.as_fd()
    }

    /// Takes in one read of the pipe made now, past the runtime (a read that would
    /// block reads nothing); whether it took in bytes.
    pub fn read_now(&mut self) -> bool {
        match nix::unistd::read(self.stream.as_fd(), &mut self.buf) {
            Err(nix::errno::Errno::EAGAIN | nix::errno::Errno::EINTR) => false,
            read => {
                let took = matches!(read, Ok(n) if n > 0);
                self.take_in(read.map_err(std::io::Error::from));
                took
            }
        }
    }

    /// Reads now, past the runtime, what the pipe holds (at most
    /// [`STDERR_READS_BEFORE_REPLY`] reads): after an answer the runtime found, whose
    /// readiness reports may lag the pipes' (a read made past the runtime leaves them
    /// behind), so that stderr written before the answer still goes with it.
    pub fn drain_now(&mut self) {
        for _ in 0..STDERR_READS_BEFORE_REPLY {
            if !self.open || !self.read_now() {
                break;
            }
        }
    }
}

/// Cuts a byte stream into lines for [`StderrReader`].
#[derive(Debug)]
struct LineSplitter {
    /// Complete lines not yet taken.
    lines: Vec<String>,
    echo: bool,
    partial: Vec<u8>,
    sent: usize,
    /// Whether [`STDERR_TRACE_FULL`] was added.
    cut: bool,
}

impl LineSplitter {
    fn new(echo: bool) -> Self {
        LineSplitter {
            lines: Vec::new(),
            echo,
            partial: Vec::new(),
            sent: 0,
            cut: false,
        }
    }

    fn push(&mut self, chunk: &[u8]) {
        // Past the trace's budget no line is kept (nor printed): nothing to cut.
        if self.cut && !self.echo {
            return;
        }
        let mut rest = chunk;
        loop {
            let (piece, newline) = match memchr::memchr(b'\n', rest) {
                Some(i) => (&rest[..i], true),
                None => (rest, false),
            };
            // A line is kept up to its cut (and one byte more, for the "…").
            let room = (STDERR_LINE_BYTES + 1).saturating_sub(self.partial.len());
            self.partial
                .extend_from_slice(&piece[..piece.len().min(room)]);
            if !newline {
                return;
            }
            self.emit();
            rest = &rest[piece.len() + 1..];
            if self.cut && !self.echo {
                return;
            }
        }
    }

    fn emit(&mut self) {
        let line = std::mem::take(&mut self.partial);
        let line = line.strip_suffix(b"\r").unwrap_or(&line);
        let text = crate::protocol::excerpt(line, STDERR_LINE_BYTES);
        if self.echo {
            eprintln!("  bot stderr | {text}");
        }
        if self.sent < STDERR_TRACE_BYTES {
            self.sent += text.len() + 1;
            self.lines.push(text);
        } else if !self.cut {
            self.cut = true;
            self.lines.push(STDERR_TRACE_FULL.to_string());
        }
    }

    /// Hands on a last line without its newline.
    fn finish(&mut self) {
        if !self.partial.is_empty() {
            self.emit();
        }
    }
}

/// The most stderr reads in a row (up to 64 KiB each) before an awaited event that is ready
/// (a reply, the bot's exit) is taken in anyway: a bot that writes stderr without end
/// cannot hold its own answer back.
pub const STDERR_READS_BEFORE_REPLY: u32 = 64;

/// Waits until the bot's stdout holds a reply line (or ends, or holds too long a line),
/// reading every stderr byte the bot wrote before it into `stderr` meanwhile (see
/// [`StderrReader::drain_while`], then [`StderrReader::drain_now`]); then
/// [`ReplyReader::line`] has the line. Cancel safe.
pub async fn next_reply<O, E>(
    replies: &mut ReplyReader<O>,
    stderr: &mut StderrReader<E>,
) -> std::io::Result<Next>
where
    O: AsyncRead + Unpin,
    E: AsyncRead + AsFd + Unpin,
{
    let next = stderr.drain_while(replies.next()).await;
    // The runtime's readiness of stdout may be older than its stderr's (a read made past
    // the runtime, [`ReplyReader::read_now`], leaves it behind): what stderr holds now
    // was written before this answer was read.
    stderr.drain_now();
    next
}

/// What a bot's stdout holds next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Next {
    /// A whole line: [`ReplyReader::line`].
    Line,
    /// More than [`MAX_LINE_BYTES`] before a newline: [`ReplyReader::partial`] has them.
    TooLong,
    /// The end of the stream, every line handed on.
    End,
}

/// The bot's reply lines: "\n"-ended lines of at most [`MAX_LINE_BYTES`] bytes (at the
/// end of the stream, the last bytes without a newline make a line too), read into one
/// buffer that never holds more than one line over the cap.
#[derive(Debug)]
pub struct ReplyReader<R> {
    stream: R,
    lines: Lines,
}

impl<R> ReplyReader<R> {
    /// Reads reply lines from `stdout`.
    pub fn new(stdout: R) -> Self {
        ReplyReader {
            stream: stdout,
            lines: Lines {
                buf: vec![0u8; REPLY_BUFFER_BYTES].into_boxed_slice(),
                start: 0,
                end: 0,
                scanned: 0,
                line_end: None,
                eof: false,
            },
        }
    }

    /// What the bytes read so far hold next (a line handed on before is dropped first);
    /// `None` while nothing whole is there and more must be read.
    pub fn look(&mut self) -> Option<Next> {
        self.lines.look()
    }

    /// The line the last [`ReplyReader::look`] found, without its newline.
    pub fn line(&self) -> &[u8] {
        let l = &self.lines;
        l.line_end.map_or(&[], |end| &l.buf[l.start..end])
    }

    /// The bytes read and not yet handed on (a line too long, for the record).
    pub fn partial(&self) -> &[u8] {
        &self.lines.buf[self.lines.start..self.lines.end]
    }
}

impl<R: AsyncRead + Unpin> ReplyReader<R> {
    /// Waits for what the stream holds next. Cancel safe.
    pub async fn next(&mut self) -> std::io::Result<Next> {
        loop {
            if let Some(next) = self.lines.look() {
                return Ok(next);
            }
            let n = self.stream.read(self.lines.room()).await?;
            self.lines.took(n);
        }
    }
}

impl<R: AsFd> ReplyReader<R> {
    /// The pipe, for a wait on it.
    pub fn pipe(&self) -> std::os::fd::BorrowedFd<'_> {
        self.stream.as_fd()
    }

    /// Takes in one read of the pipe made now, past the runtime: for a pipe just found
    /// ready (a read that would block reads nothing), when [`ReplyReader::look`] found
    /// nothing whole (with a line still handed on, it reads nothing).
    ///
    /// # Errors
    /// The read failed.
    pub fn read_now(&mut self) -> std::io::Result<()> {
        if self.lines.line_end.is_some() {
            return Ok(());
        }
        match nix::unistd::read(self.stream.as_fd(), self.lines.room()) {
            Ok(n) => self.lines.took(n),
            Err(nix::errno::Errno::EAGAIN | nix::errno::Errno::EINTR) => {}
            Err(e) => return Err(e.into()),
        }
        Ok(())
    }
}

/// The least room a reply buffer leaves for a read.
const READ_BYTES: usize = 16 * 1024;

/// How much a reply buffer holds: a line over the cap, and room for one more read.
const REPLY_BUFFER_BYTES: usize = MAX_LINE_BYTES + 1 + READ_BYTES;

/// A [`ReplyReader`]'s buffer: the bytes read from `start` to `end`.
#[derive(Debug)]
struct Lines {
    buf: Box<[u8]>,
    /// The first byte not yet handed on.
    start: usize,
    /// The end of the bytes read.
    end: usize,
    /// How far past `start` a newline has been looked for.
    scanned: usize,
    /// The end of the line handed on by the last `look` (from `start`).
    line_end: Option<usize>,
    /// The stream ended.
    eof: bool,
}

impl Lines {
    fn look(&mut self) -> Option<Next> {
        self.drop_line();
        let read_to = self.end.min(self.start + MAX_LINE_BYTES + 1);
        let from = self.start + self.scanned;
        if let Some(i) = self.buf[from..read_to].iter().position(|&b| b == b'\n') {
            self.line_end = Some(from + i);
            return Some(Next::Line);
        }
        if self.end - self.start > MAX_LINE_BYTES {
            return Some(Next::TooLong);
        }
        self.scanned = read_to - self.start;
        if !self.eof {
            return None;
        }
        if self.end > self.start {
            // The last bytes, without a newline.
            self.line_end = Some(self.end);
            return Some(Next::Line);
        }
        Some(Next::End)
    }

    fn drop_line(&mut self) {
        if let Some(end) = self.line_end.take() {
            self.start = (end + 1).min(self.end);
            self.scanned = 0;
        }
    }

    /// Room for the next read, after moving what is kept to the front when it is
    /// needed. Never empty after `look` found nothing whole: the buffer holds a line
    /// over the cap and a read more.
    fn room(&mut self) -> &mut [u8] {
        self.drop_line();
        if self.start == self.end {
            (self.start, self.end) = (0, 0);
        } else if self.buf.len() - self.end < READ_BYTES {
            self.buf.copy_within(self.start..self.end, 0);
            (self.end, self.start) = (self.end - self.start, 0);
        }
        &mut self.buf[self.end..]
    }

    /// Counts `read` more bytes in the room (none: the end of the stream).
    fn took(&mut self, read: usize) {
        if read == 0 {
            self.eof = true;
        }
        self.end += read;
    }
}

/// The last bytes of a stream, up to a cap, and how many came in all. Kept in a buffer
/// of up to twice the cap that drops its oldest half when full, so that taking in a
/// chunk costs copying it (and now and then moving a cap's worth), never a byte at a time.
#[derive(Debug)]
struct Tail {
    cap: usize,
    kept: Vec<u8>,
    total: u64,
}

impl Tail {
    fn new(cap: usize) -> Self {
        Tail {
            cap,
            kept: Vec::with_capacity(cap.min(8192)),
            total: 0,
        }
    }

    fn push(&mut self, chunk: &[u8]) {
        self.total += chunk.len() as u64;
        if chunk.len() >= self.cap {
            self.kept.clear();
            self.kept
                .extend_from_slice(&chunk[chunk.len() - self.cap..]);
            return;
        }
        if self.kept.len() + chunk.len() > 2 * self.cap {
            let keep_from = self.kept.len() - (self.cap - chunk.len());
            self.kept.drain(..keep_from);
        }
        self.kept.extend_from_slice(chunk);
    }

    /// The tail as text (lossy UTF-8), prefixed with a note of how much was cut.
    fn into_text(self) -> String {
        let from = self.kept.len().saturating_sub(self.cap);
        let kept = &self.kept[from..];
        let text = String::from_utf8_lossy(kept).into_owned();
        if self.total > kept.len() as u64 {
            format!(
                "[... {} earlier bytes of stderr not kept]\n{text}",
                self.total - kept.len() as u64
            )
        } else {
            text
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_matchs_stderr_lines_stop_at_their_budget_with_one_line_saying_so() {
        let mut split = LineSplitter::new(false);
        let line = format!("{}\n", "x".repeat(99));
        for _ in 0..(STDERR_TRACE_BYTES / 100 + 50) {
            split.push(line.as_bytes());
        }
        let kept: usize = split.lines.iter().map(|l| l.len() + 1).sum();
        assert!(kept <= STDERR_TRACE_BYTES + 200, "{kept}");
        assert_eq!(
            split.lines.last().map(String::as_str),
            Some(STDERR_TRACE_FULL)
        );
        assert_eq!(
            split
                .lines
                .iter()
                .filter(|l| *l == STDERR_TRACE_FULL)
                .count(),
            1
        );
    }
    /// The next line of `r`, `None` at the end; a line too long is an error.
    async fn next_line<R: AsyncRead + Unpin>(
        r: &mut ReplyReader<R>,
    ) -> Option<Result<Vec<u8>, ()>> {
        match r.next().await.unwrap() {
            Next::Line => Some(Ok(r.line().to_vec())),
            Next::TooLong => Some(Err(())),
            Next::End => None,
        }
    }

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
        let mut r = ReplyReader::new(rx);
        assert_eq!(
            next_line(&mut r).await.unwrap().unwrap(),
            b"{\"rotation\":0,\"movement\":1}"
        );
        assert_eq!(
            next_line(&mut r).await.unwrap().unwrap(),
            b"{\"reset\":true}"
        );
        writer.await.unwrap();
        assert!(next_line(&mut r).await.is_none());
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
        let mut r = ReplyReader::new(rx);
        assert!(next_line(&mut r).await.unwrap().is_err());
        assert!(r.partial().len() <= MAX_LINE_BYTES + 1 + READ_BYTES);
        drop(r);
        writer.await.unwrap();
    }

    #[tokio::test]
    async fn a_line_of_exactly_64_kib_is_accepted() {
        let mut data = vec![b' '; MAX_LINE_BYTES];
        data.push(b'\n');
        let mut r = ReplyReader::new(&data[..]);
        assert_eq!(
            next_line(&mut r).await.unwrap().unwrap().len(),
            MAX_LINE_BYTES
        );
        let mut data = vec![b' '; MAX_LINE_BYTES + 1];
        data.push(b'\n');
        let mut r = ReplyReader::new(&data[..]);
        assert!(next_line(&mut r).await.unwrap().is_err());
    }

    #[tokio::test]
    async fn stderr_lines_are_handed_on_one_by_one_and_cut() {
        let (mut tx, rx) = tokio::net::unix::pipe::pipe().unwrap();
        let long = "y".repeat(STDERR_LINE_BYTES + 100);
        let data = format!("one\r\ntwo\n{long}\nlast without newline");
        tokio::io::AsyncWriteExt::write_all(&mut tx, data.as_bytes())
            .await
            .unwrap();
        drop(tx);
        let reader = StderrReader::new(rx, 1000, false);
        let (tail, got) = reader.finish(std::time::Duration::from_secs(10)).await;
        assert!(tail.ends_with("last without newline"));
        assert_eq!(got[..2], ["one", "two"]);
        assert!(got[2].ends_with('…') && got[2].len() < STDERR_LINE_BYTES + 10);
        assert_eq!(got[3], "last without newline");
        assert_eq!(got.len(), 4);
    }

    #[tokio::test]
    async fn a_stderr_left_open_ends_the_tail_with_a_note() {
        let (tx, rx) = tokio::net::unix::pipe::pipe().unwrap();
        nix::unistd::write(&tx, b"half a line").unwrap();
        let reader = StderrReader::new(rx, 1000, false);
        let (tail, got) = reader.finish(std::time::Duration::from_millis(100)).await;
        assert_eq!(tail, "half a line\n[stderr could not be read to its end]");
        assert_eq!(got, ["half a line"]);
        drop(tx);
    }

    /// Two pipes standing for a bot's stdout and stderr.
    fn bot_pipes() -> (
        tokio::net::unix::pipe::Sender,
        ReplyReader<tokio::net::unix::pipe::Receiver>,
        tokio::net::unix::pipe::Sender,
        StderrReader<tokio::net::unix::pipe::Receiver>,
    ) {
        let (out_tx, out_rx) = tokio::net::unix::pipe::pipe().unwrap();
        let (err_tx, err_rx) = tokio::net::unix::pipe::pipe().unwrap();
        (
            out_tx,
            ReplyReader::new(out_rx),
            err_tx,
            StderrReader::new(err_rx, 1_000_000, false),
        )
    }

    #[tokio::test]
    async fn stderr_written_before_an_answer_is_read_before_it() {
        // Both writes are done before the reader looks: the answer is ready at once, and
        // only the order of the kernel's readiness reports can put the stderr first.
        let (out, mut replies, err, mut stderr) = bot_pipes();
        for step in 1..=200 {
            for line in 0..step % 3 {
                let text = format!("step {step} line {line}\n");
                assert_eq!(
                    nix::unistd::write(&err, text.as_bytes()).unwrap(),
                    text.len()
                );
            }
            let answer = format!("answer {step}\n");
            nix::unistd::write(&out, answer.as_bytes()).unwrap();
            assert_eq!(
                next_reply(&mut replies, &mut stderr).await.unwrap(),
                Next::Line
            );
            assert_eq!(replies.line(), format!("answer {step}").as_bytes());
            let want: Vec<String> = (0..step % 3)
                .map(|l| format!("step {step} line {l}"))
                .collect();
            assert_eq!(stderr.take_lines(), want, "step {step}");
        }
    }

    #[tokio::test]
    async fn stderr_before_an_answer_is_read_before_it_after_reads_past_the_runtime() {
        let (out, mut replies, err, mut stderr) = bot_pipes();
        // The runtime has found stderr empty (its readiness cleared)...
        let _ = tokio::time::timeout(Duration::from_millis(5), stderr.read_some()).await;
        // ...and stdout ready, but the answer was read past it (its readiness left set
        // on an empty pipe), as the near wait does.
        nix::unistd::write(&out, b"first\n").unwrap();
        tokio::time::sleep(Duration::from_millis(5)).await;
        assert_eq!(replies.look(), None);
        replies.read_now().unwrap();
        assert_eq!(replies.look(), Some(Next::Line));
        // A line on stderr, then the answer, with no turn of the runtime between them
        // and the wait: the stale readiness of stdout could take the answer first.
        nix::unistd::write(&err, b"thinking\n").unwrap();
        nix::unistd::write(&out, b"second\n").unwrap();
        assert_eq!(
            next_reply(&mut replies, &mut stderr).await.unwrap(),
            Next::Line
        );
        assert_eq!(replies.line(), b"second");
        assert_eq!(stderr.take_lines(), ["thinking"]);
        drop((out, err));
    }

    #[tokio::test]
    async fn a_bot_that_writes_stderr_without_end_still_has_its_answer_read() {
        // stderr keeps coming, from before the answer to after it (32 MiB through a full
        // pipe): the answer is taken after a bounded number of stderr reads (in a row
        // before it, and at once after it), the rest of the stderr later.
        let (out, mut replies, err, mut stderr) = bot_pipes();
        nix::unistd::write(&out, b"answer\n").unwrap();
        let writer = std::thread::spawn(move || {
            let chunk = vec![b'x'; 4096];
            let mut sent = 0;
            while sent < 32 << 20 {
                match nix::unistd::write(&err, &chunk) {
                    Ok(n) => sent += n,
                    Err(nix::errno::Errno::EAGAIN) => std::thread::yield_now(),
                    Err(_) => break,
                }
            }
        });
        tokio::time::sleep(Duration::from_millis(20)).await;
        let next = tokio::time::timeout(
            Duration::from_secs(10),
            next_reply(&mut replies, &mut stderr),
        )
        .await
        .expect("the answer is taken despite the flood");
        assert_eq!(next.unwrap(), Next::Line);
        assert_eq!(replies.line(), b"answer");
        let bound = 2 * STDERR_READS_BEFORE_REPLY as u64 * stderr.buf.len() as u64;
        assert!(
            stderr.tail.total <= bound,
            "{} > {bound}",
            stderr.tail.total
        );
        drop((out, stderr));
        writer.join().unwrap();
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
