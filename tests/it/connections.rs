//! A server that keeps its connections: idle and slow clients are closed after the head
//! timeout, one address cannot hold more than its cap, and `/healthz` and the match
//! workers keep working while 1,000 idle connections are open.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use crate::support::{TestServer, register, simple_bot_files, wait_match};

/// A connection from `source` to the server that sent half a request line and waits.
fn idle_from(server: &SocketAddr, source: &str) -> std::io::Result<TcpStream> {
    let socket = socket2::Socket::new(socket2::Domain::IPV4, socket2::Type::STREAM, None)?;
    socket.bind(&format!("{source}:0").parse::<SocketAddr>().unwrap().into())?;
    socket.connect(&(*server).into())?;
    let mut stream: TcpStream = socket.into();
    stream.write_all(b"GET /healthz HT")?;
    Ok(stream)
}

/// Whether the server has closed `stream` (a read gives end of file or an error) within
/// `wait`.
fn closed_within(stream: &mut TcpStream, wait: Duration) -> bool {
    stream.set_read_timeout(Some(wait)).unwrap();
    let mut buf = [0u8; 256];
    match stream.read(&mut buf) {
        Ok(0) => true,
        // An answer (408 or 400) before closing counts as closed: read on to the end.
        Ok(_) => {
            let deadline = Instant::now() + wait;
            while Instant::now() < deadline {
                match stream.read(&mut buf) {
                    Ok(0) => return true,
                    Ok(_) => {}
                    Err(e) if is_timeout(&e) => {}
                    Err(_) => return true,
                }
            }
            false
        }
        Err(e) => !is_timeout(&e),
    }
}

/// Whether a read failed only because nothing came within its timeout.
fn is_timeout(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_thousand_idle_connections_neither_stop_healthz_nor_the_workers_and_are_closed() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(
        dir.path(),
        &[
            "--jobs",
            "1",
            "--head-timeout-secs",
            "8",
            "--max-connections-per-address",
            "250",
        ],
    );
    let addr: SocketAddr = server.base.trim_start_matches("http://").parse().unwrap();
    // 1,000 idle connections from four other loopback addresses, 250 each (their cap).
    let opened = Instant::now();
    let mut idle = Vec::new();
    for source in ["127.0.0.2", "127.0.0.3", "127.0.0.4", "127.0.0.5"] {
        for _ in 0..250 {
            idle.push(idle_from(&addr, source).unwrap());
        }
    }
    // Everyone else is served meanwhile (connections are taken in order: once this is
    // answered, the 1,000 are all open on the server's side), and the workers play.
    let (status, health) = server.get("/healthz", None).await;
    assert_eq!(status, 200, "{health}");
    // One more from an address at its cap is closed at once, without an answer.
    let mut over = idle_from(&addr, "127.0.0.2").unwrap();
    assert!(closed_within(&mut over, Duration::from_secs(2)));
    let (bot, token) = register(
        &server,
        "honest",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let id = crate::support::queue(&server, bot, 1, 1, &token).await;
    let m = wait_match(&server, id).await;
    assert_eq!(m["status"], "finished", "{m}");
    // Still open while within the head timeout (if the above was quick enough to tell).
    if opened.elapsed() < Duration::from_secs(6) {
        assert!(!closed_within(&mut idle[0], Duration::from_millis(100)));
    }
    // Past the head timeout every idle connection is closed by the server (the last
    // ones accepted latest: give a loaded machine some seconds more).
    tokio::time::sleep(Duration::from_secs(8).saturating_sub(opened.elapsed())).await;
    let still_open = tokio::task::spawn_blocking(move || {
        let deadline = Instant::now() + Duration::from_secs(20);
        let mut open: Vec<TcpStream> = idle;
        while !open.is_empty() && Instant::now() < deadline {
            open.retain_mut(|s| !closed_within(s, Duration::from_millis(20)));
        }
        open.len()
    })
    .await
    .unwrap();
    assert_eq!(still_open, 0, "idle connections the server kept");
    let (status, _) = server.get("/healthz", None).await;
    assert_eq!(status, 200);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_http2_client_cannot_hold_a_connection_past_the_head_timeout() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "0", "--head-timeout-secs", "2"]);
    let addr: SocketAddr = server.base.trim_start_matches("http://").parse().unwrap();
    // The HTTP/2 preface and an empty SETTINGS frame (h2c, prior knowledge), then nothing.
    let mut stream = TcpStream::connect(addr).unwrap();
    stream
        .write_all(b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n\0\0\0\x04\0\0\0\0\0")
        .unwrap();
    let closed = tokio::task::spawn_blocking(move || {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            if closed_within(&mut stream, Duration::from_millis(200)) {
                return true;
            }
            if Instant::now() > deadline {
                return false;
            }
        }
    })
    .await
    .unwrap();
    assert!(
        closed,
        "an HTTP/2 connection stayed open past the head timeout"
    );
    let (status, _) = server.get("/healthz", None).await;
    assert_eq!(status, 200);
}
