//! `gdsky preview`'s server without a browser (issue #23, item 2): bound to 127.0.0.1 only; a
//! path-traversal request, a foreign `Origin` and a foreign `Host` (DNS rebinding) refused; and
//! the routes it does serve.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Stdio};

struct Server(Child, u16);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn start() -> Server {
    let mut child = skytest::gdsky!()
        .command()
        .args(["preview", "--no-open", "--port", "0", "--size", "16x8"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("gdsky preview starts");
    let mut line = String::new();
    let mut out = BufReader::new(child.stdout.take().expect("stdout"));
    out.read_line(&mut line).expect("the address");
    std::thread::spawn(move || for _ in out.lines() {});
    let port = line
        .split("127.0.0.1:")
        .nth(1)
        .and_then(|rest| rest.split('/').next())
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no address in {line:?}"));
    Server(child, port)
}

/// Sends a raw request; returns the status code and the body.
fn request(port: u16, head: &str) -> (u16, String) {
    let mut stream = TcpStream::connect(("127.0.0.1", port)).expect("connects");
    stream.write_all(format!("{head}\r\nConnection: close\r\n\r\n").as_bytes()).expect("sends");
    let mut response = String::new();
    stream.read_to_string(&mut response).expect("reads");
    let status = response.split(' ').nth(1).and_then(|s| s.parse().ok()).unwrap_or(0);
    (status, response.split("\r\n\r\n").nth(1).unwrap_or("").to_string())
}

#[test]
fn the_server_listens_on_loopback_only_and_refuses_what_it_does_not_serve() {
    let server = start();
    let port = server.1;
    let host = format!("Host: 127.0.0.1:{port}");
    // The listening socket, as the kernel lists it: 127.0.0.1 (0100007F), never 0.0.0.0.
    let tcp = std::fs::read_to_string("/proc/net/tcp").expect("/proc/net/tcp");
    let listening: Vec<&str> = tcp
        .lines()
        .filter(|l| l.split_whitespace().nth(3) == Some("0A"))
        .filter_map(|l| l.split_whitespace().nth(1))
        .filter(|local| local.ends_with(&format!(":{port:04X}")))
        .collect();
    assert_eq!(listening, [format!("0100007F:{port:04X}")], "{tcp}");

    let (status, body) = request(port, &format!("GET / HTTP/1.1\r\n{host}"));
    assert_eq!(status, 200);
    assert!(body.contains("gdsky preview"), "{body}");
    let (status, body) = request(port, &format!("GET /state.json HTTP/1.1\r\n{host}"));
    assert_eq!(status, 200);
    assert!(body.contains("\"wgsl\"") && body.contains("fs_panorama"), "{body}");

    // Nothing by path: traversal in every spelling is just an unknown route.
    for path in [
        "/../../../../etc/passwd",
        "/%2e%2e/%2e%2e/etc/passwd",
        "/texture/../../etc/passwd",
        "/texture/99",
        "//etc/passwd",
    ] {
        let (status, body) = request(port, &format!("GET {path} HTTP/1.1\r\n{host}"));
        assert_eq!(status, 404, "{path}: {body}");
        assert!(!body.contains("root:"), "{path}: {body}");
    }
    // Another site's page (a foreign Origin) and DNS rebinding (a foreign Host) get 403.
    let (status, _) = request(port, &format!("GET /state.json HTTP/1.1\r\n{host}\r\nOrigin: http://evil.example"));
    assert_eq!(status, 403);
    let (status, _) = request(port, "GET /state.json HTTP/1.1\r\nHost: evil.example");
    assert_eq!(status, 403);
    let (status, _) = request(port, &format!("GET /state.json HTTP/1.1\r\n{host}\r\nOrigin: http://127.0.0.1:{port}"));
    assert_eq!(status, 200, "the page's own origin");
    let (status, _) = request(port, &format!("POST /state.json HTTP/1.1\r\n{host}\r\nContent-Length: 0"));
    assert_eq!(status, 405);
}
