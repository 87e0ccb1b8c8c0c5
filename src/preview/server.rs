//! The local HTTP server (tiny_http), its routes and checks, the file watcher (notify) and the
//! server-sent events that tell the page a new state is ready.

use super::lavapipe::Renderer;
use super::state::PageState;
use crate::engine::Error;
use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

/// The page and its script, built into the binary.
const PAGE_HTML: &str = include_str!("page.html");
const PAGE_JS: &str = include_str!("preview.js");

/// Why the server could not start.
#[derive(Debug)]
pub struct PreviewError(pub String);

impl std::fmt::Display for PreviewError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PreviewError {}

/// What the page is shown: the last good state, the current error, and a version that changes
/// with either.
#[derive(Default)]
struct Shared {
    good: Option<PageState>,
    error: Option<String>,
    version: u64,
}

/// A running preview server: bound, serving, watching its input.
pub struct Preview {
    server: Arc<tiny_http::Server>,
    addr: SocketAddr,
    shared: Arc<(Mutex<Shared>, Condvar)>,
    stop: Arc<AtomicBool>,
}

impl Preview {
    /// Binds `127.0.0.1:port` (0: any free port) and loads the first state with `reload`. A
    /// first load that fails is served as an error page state (the diagnostic), not refused:
    /// the author fixes the file and the page follows.
    pub fn bind(port: u16, reload: &mut dyn FnMut() -> Result<PageState, Error>) -> Result<Preview, PreviewError> {
        let server = tiny_http::Server::http(("127.0.0.1", port))
            .map_err(|e| PreviewError(format!("cannot listen on 127.0.0.1:{port}: {e}")))?;
        let addr = server.server_addr().to_ip().ok_or_else(|| PreviewError("the server has no IP address".into()))?;
        let mut shared = Shared::default();
        match reload() {
            Ok(state) => shared.good = Some(state),
            Err(e) => shared.error = Some(e.render(false)),
        }
        Ok(Preview {
            server: Arc::new(server),
            addr,
            shared: Arc::new((Mutex::new(shared), Condvar::new())),
            stop: Arc::new(AtomicBool::new(false)),
        })
    }

    /// The page's address, `http://127.0.0.1:PORT/`.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// A flag that ends [`Preview::serve`] when set (Ctrl-C sets it in the CLI).
    pub fn stop_flag(&self) -> Arc<AtomicBool> {
        self.stop.clone()
    }

    /// Serves until the stop flag is set, reloading with `reload` whenever a watched file
    /// changes. `changed` is told each reload's outcome (`Ok(version)` or the error's text).
    pub fn serve(
        &self,
        mut reload: Box<dyn FnMut() -> Result<PageState, Error> + Send>,
        changed: Box<dyn Fn(Result<u64, String>) + Send>,
    ) -> Result<(), PreviewError> {
        let (events_tx, events_rx) = std::sync::mpsc::channel::<()>();
        let mut watcher = notify::recommended_watcher(move |event: notify::Result<notify::Event>| {
            if event.is_ok_and(|e| !matches!(e.kind, notify::EventKind::Access(_))) {
                let _ = events_tx.send(());
            }
        })
        .map_err(|e| PreviewError(format!("cannot watch files: {e}")))?;
        let mut watching: Vec<PathBuf> = Vec::new();
        let rewatch = |watcher: &mut notify::RecommendedWatcher, watching: &mut Vec<PathBuf>, files: &[PathBuf]| {
            use notify::Watcher;
            // Folders, not files: editors replace a file by renaming a new one over it.
            let mut folders: Vec<PathBuf> = files
                .iter()
                .filter_map(|f| std::fs::canonicalize(f).ok())
                .filter_map(|f| f.parent().map(PathBuf::from))
                .collect();
            folders.sort();
            folders.dedup();
            for old in watching.iter().filter(|d| !folders.contains(d)) {
                let _ = watcher.unwatch(old);
            }
            for new in folders.iter().filter(|d| !watching.contains(d)) {
                let _ = watcher.watch(new, notify::RecursiveMode::NonRecursive);
            }
            *watching = folders;
        };
        let files_of = |shared: &Shared| shared.good.as_ref().map(|g| g.watched.clone()).unwrap_or_default();
        let initial = files_of(&*self.shared.0.lock().map_err(|_| PreviewError("state lock poisoned".into()))?);
        let mut files = initial;
        rewatch(&mut watcher, &mut watching, &files);

        let server = self.server.clone();
        let renderer = Arc::new(Renderer::default());
        let shared = self.shared.clone();
        let addr = self.addr;
        let stop = self.stop.clone();
        let accept = std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                match server.recv_timeout(Duration::from_millis(100)) {
                    Ok(Some(request)) => {
                        let (shared, stop, renderer) = (shared.clone(), stop.clone(), renderer.clone());
                        std::thread::spawn(move || respond(request, addr, &shared, &stop, &renderer));
                    }
                    Ok(None) => {}
                    Err(_) => break,
                }
            }
        });

        while !self.stop.load(Ordering::Relaxed) {
            match events_rx.recv_timeout(Duration::from_millis(100)) {
                Ok(()) => {}
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => continue,
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
            }
            // An editor's save is several events (write, rename, chmod): settle, then reload once.
            std::thread::sleep(Duration::from_millis(30));
            while events_rx.try_recv().is_ok() {}
            let outcome = reload();
            let (lock, bell) = &*self.shared;
            let mut now = lock.lock().map_err(|_| PreviewError("state lock poisoned".into()))?;
            match outcome {
                Ok(state) => {
                    // Only a change to what the page shows is a new version.
                    if now.error.is_none() && now.good.as_ref().is_some_and(|g| same(g, &state)) {
                        continue;
                    }
                    files = state.watched.clone();
                    now.good = Some(state);
                    now.error = None;
                    now.version += 1;
                    changed(Ok(now.version));
                }
                Err(e) => {
                    let text = e.render(false);
                    if now.error.as_deref() == Some(text.as_str()) {
                        continue;
                    }
                    now.error = Some(text.clone());
                    now.version += 1;
                    changed(Err(text));
                }
            }
            bell.notify_all();
            drop(now);
            rewatch(&mut watcher, &mut watching, &files);
        }
        self.stop.store(true, Ordering::Relaxed);
        self.shared.1.notify_all();
        self.server.unblock();
        let _ = accept.join();
        Ok(())
    }
}

/// Whether two states show the same thing.
fn same(a: &PageState, b: &PageState) -> bool {
    a.state == b.state && a.material == b.material && a.textures == b.textures
}

/// Answers one request: the checks, then the route.
fn respond(
    request: tiny_http::Request,
    addr: SocketAddr,
    shared: &Arc<(Mutex<Shared>, Condvar)>,
    stop: &AtomicBool,
    renderer: &Renderer,
) {
    use tiny_http::{Header, Response, StatusCode};
    let header = |name: &'static str| {
        request.headers().iter().find(|h| h.field.equiv(name)).map(|h| h.value.as_str().to_string())
    };
    let port = addr.port();
    let hosts = [format!("127.0.0.1:{port}"), format!("localhost:{port}")];
    let host_ok = header("Host").is_some_and(|h| hosts.contains(&h));
    let origin_ok = header("Origin").is_none_or(|o| hosts.iter().any(|h| o == format!("http://{h}")));
    let text = |status: u16, body: &str| {
        Response::from_string(body)
            .with_status_code(StatusCode(status))
            .with_header(content_type("text/plain; charset=utf-8"))
    };
    if !host_ok || !origin_ok {
        let _ = request.respond(text(403, "403: gdsky preview answers only its own page on 127.0.0.1\n"));
        return;
    }
    let path = request.url().split('?').next().unwrap_or("").to_string();
    if *request.method() == tiny_http::Method::Post && path == "/render" {
        render(request, shared, renderer);
        return;
    }
    if *request.method() != tiny_http::Method::Get {
        let _ = request.respond(text(405, "405: only GET, and POST /render\n"));
        return;
    }
    let snapshot = |f: &dyn Fn(&Shared) -> Option<Body>| shared.0.lock().ok().and_then(|s| f(&s));
    let body = match path.as_str() {
        "/" | "/index.html" => Some((PAGE_HTML.as_bytes().to_vec(), "text/html; charset=utf-8")),
        "/preview.js" => Some((PAGE_JS.as_bytes().to_vec(), "text/javascript; charset=utf-8")),
        "/state.json" => snapshot(&|s| {
            let mut state = s.good.as_ref().map(|g| g.state.clone()).unwrap_or_else(|| serde_json::json!({}));
            state["version"] = serde_json::json!(s.version);
            state["error"] = serde_json::json!(s.error);
            Some((state.to_string().into_bytes(), "application/json"))
        }),
        "/material.bin" => snapshot(&|s| Some((s.good.as_ref()?.material.clone(), "application/octet-stream"))),
        // Browsers ask for it unbidden; nothing, rather than a 404 in the page's console.
        "/favicon.ico" => Some((Vec::new(), "image/x-icon")),
        "/events" => {
            events(request, shared, stop);
            return;
        }
        other => other
            .strip_prefix("/texture/")
            .and_then(|i| i.parse::<usize>().ok())
            .and_then(|i| snapshot(&|s| Some((s.good.as_ref()?.textures.get(i)?.clone(), "application/octet-stream")))),
    };
    let response = match body {
        Some((bytes, kind)) => Response::from_data(bytes)
            .with_header(content_type(kind))
            .with_header(Header::from_bytes("Cache-Control", "no-store").expect("a valid header")),
        None => {
            let _ = request.respond(text(404, "404: not something gdsky preview serves\n"));
            return;
        }
    };
    let _ = request.respond(response);
}

/// `POST /render`: the JSON body (at most 1 MiB) rendered by [`Renderer`] with the last good
/// state's shader; 400 with the reason for a body it cannot render.
fn render(mut request: tiny_http::Request, shared: &Arc<(Mutex<Shared>, Condvar)>, renderer: &Renderer) {
    use std::io::Read;
    use tiny_http::{Header, Response, StatusCode};
    let fail = |status: u16, message: String| {
        Response::from_string(format!("{message}\n"))
            .with_status_code(StatusCode(status))
            .with_header(content_type("text/plain; charset=utf-8"))
    };
    let mut body = Vec::new();
    if request.as_reader().take((1 << 20) + 1).read_to_end(&mut body).is_err() || body.len() > 1 << 20 {
        let _ = request.respond(fail(400, "the body is not readable or over 1 MiB".into()));
        return;
    }
    let sky = shared.0.lock().ok().and_then(|s| s.good.as_ref().and_then(|g| g.sky.clone()));
    let Some(sky) = sky else {
        let _ = request.respond(fail(409, "no shader has converted yet".into()));
        return;
    };
    let outcome =
        serde_json::from_slice(&body).map_err(|e| format!("not JSON: {e}")).and_then(|v| renderer.render(&sky, &v));
    let response = match outcome {
        Ok((width, height, pixels)) => {
            let bytes: Vec<u8> = pixels.iter().flat_map(|p| p.iter().flat_map(|c| c.to_le_bytes())).collect();
            Response::from_data(bytes)
                .with_header(content_type("application/octet-stream"))
                .with_header(Header::from_bytes("X-Width", width.to_string()).expect("a valid header"))
                .with_header(Header::from_bytes("X-Height", height.to_string()).expect("a valid header"))
        }
        Err(message) => fail(400, message),
    };
    let _ = request.respond(response);
}

/// A response body and its content type.
type Body = (Vec<u8>, &'static str);

/// A `Content-Type` header.
fn content_type(kind: &str) -> tiny_http::Header {
    tiny_http::Header::from_bytes("Content-Type", kind).expect("a valid header")
}

/// `/events`: server-sent events, one `state` event with the version now and one each time it
/// changes, until the page goes away or the server stops. Written on the raw connection and
/// flushed per event (a chunked response would buffer them).
fn events(request: tiny_http::Request, shared: &Arc<(Mutex<Shared>, Condvar)>, stop: &AtomicBool) {
    let mut writer = request.into_writer();
    let head =
        "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n";
    if writer.write_all(head.as_bytes()).and_then(|()| writer.flush()).is_err() {
        return;
    }
    let (lock, bell) = &**shared;
    let mut seen = None;
    loop {
        let Ok(guard) = lock.lock() else { return };
        let Ok((guard, _)) = bell.wait_timeout_while(guard, Duration::from_secs(15), |s| {
            Some(s.version) == seen && !stop.load(Ordering::Relaxed)
        }) else {
            return;
        };
        let version = guard.version;
        drop(guard);
        if stop.load(Ordering::Relaxed) {
            return;
        }
        // A comment line every 15 s keeps the connection open through idle proxies and tells
        // the thread when the page has gone.
        let message = if Some(version) == seen {
            ": still here\n\n".to_string()
        } else {
            format!("event: state\ndata: {version}\n\n")
        };
        if writer.write_all(message.as_bytes()).and_then(|()| writer.flush()).is_err() {
            return;
        }
        seen = Some(version);
    }
}
