//! The oracle's processes: `node driver.mjs`, which starts Chromium through playwright-core. They
//! run in a process group of their own, talk JSON lines over the driver's stdin/stdout, and are
//! ended together.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Write};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::OracleError;
use crate::install::Installation;

/// How many of the driver's last stderr lines are kept for error messages.
const STDERR_LINES: usize = 40;

/// A temporary directory removed on drop.
pub(crate) struct WorkDir(PathBuf);

impl WorkDir {
    pub fn create() -> std::io::Result<Self> {
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
        let path = std::env::temp_dir().join(format!("skyoracle-{}-{nanos}", std::process::id()));
        std::fs::create_dir(&path)?;
        Ok(Self(path))
    }

    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for WorkDir {
    fn drop(&mut self) {
        // Best effort: a leftover temporary directory is harmless.
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The running driver.
pub(crate) struct Driver {
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<String>,
    stderr: Arc<Mutex<VecDeque<String>>>,
    stopped: bool,
}

impl Driver {
    /// Starts `node driver.mjs ORACLE_DIR WORK_DIR CHROMIUM` in a new process group.
    pub fn spawn(install: &Installation, driver: &Path, work_dir: &Path) -> std::io::Result<Self> {
        let mut child = Command::new(&install.node)
            .arg(driver)
            .arg(&install.oracle_dir)
            .arg(work_dir)
            .arg(&install.chromium)
            // Chromium's helpers follow the driver into this group, so one killpg ends them all.
            .process_group(0)
            // playwright-core must never fetch a browser of its own.
            .env("PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD", "1")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        let stdout = child.stdout.take().ok_or_else(|| std::io::Error::other("no stdout pipe"))?;
        let stderr_pipe = child.stderr.take().ok_or_else(|| std::io::Error::other("no stderr pipe"))?;
        let stdin = child.stdin.take();

        let (tx, lines) = mpsc::channel();
        thread::spawn(move || {
            // Ends at EOF, on a read error or when the receiver is gone; the channel's
            // disconnection tells the receiver.
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let stderr = Arc::new(Mutex::new(VecDeque::with_capacity(STDERR_LINES)));
        let tail = Arc::clone(&stderr);
        thread::spawn(move || {
            for line in BufReader::new(stderr_pipe).lines().map_while(Result::ok) {
                if std::env::var_os("SKYORACLE_DEBUG").is_some() {
                    eprintln!("{line}");
                }
                if let Ok(mut tail) = tail.lock() {
                    if tail.len() == STDERR_LINES {
                        tail.pop_front();
                    }
                    tail.push_back(line);
                }
            }
        });
        Ok(Self { child, stdin, lines, stderr, stopped: false })
    }

    /// The driver's last stderr lines, joined.
    pub fn stderr_tail(&self) -> String {
        self.stderr.lock().map(|t| t.iter().cloned().collect::<Vec<_>>().join("\n")).unwrap_or_default()
    }

    /// Sends one JSON line.
    pub fn send(&mut self, message: &Value) -> Result<(), OracleError> {
        let mut line = message.to_string();
        line.push('\n');
        let stdin = self.stdin.as_mut().ok_or_else(|| OracleError::Dead("the driver's stdin is closed".into()))?;
        stdin
            .write_all(line.as_bytes())
            .and_then(|()| stdin.flush())
            .map_err(|e| self.crashed(format!("writing a job: {e}")))
    }

    /// Waits up to `timeout` for the next JSON line. A `fatal` event from the driver, its exit
    /// and the time running out are errors.
    pub fn recv(&mut self, timeout: Duration, what: &str) -> Result<Value, OracleError> {
        let line = match self.lines.recv_timeout(timeout) {
            Ok(line) => line,
            Err(RecvTimeoutError::Timeout) => {
                return Err(OracleError::Timeout { what: what.to_string(), after: timeout });
            }
            Err(RecvTimeoutError::Disconnected) => {
                // Give the exit status a moment to appear, for the message.
                let status = (0..20)
                    .find_map(|_| match self.child.try_wait() {
                        Ok(Some(status)) => Some(status.to_string()),
                        _ => {
                            thread::sleep(Duration::from_millis(25));
                            None
                        }
                    })
                    .unwrap_or_else(|| "still running".into());
                return Err(self.crashed(format!("the driver closed its output ({status}) during {what}")));
            }
        };
        let value: Value = serde_json::from_str(&line)
            .map_err(|e| OracleError::Protocol(format!("a driver line is not JSON ({e}): {line:.200}")))?;
        if value.get("event").and_then(Value::as_str) == Some("fatal") {
            let message = value.get("message").and_then(Value::as_str).unwrap_or("(no message)");
            // The driver enforces the job's own time limit before ours runs out.
            if value.get("kind").and_then(Value::as_str) == Some("timeout") {
                return Err(OracleError::Timeout { what: format!("{what}: {message}"), after: timeout });
            }
            return Err(self.crashed(message.to_string()));
        }
        Ok(value)
    }

    fn crashed(&self, message: String) -> OracleError {
        OracleError::Crashed { message, stderr_tail: self.stderr_tail() }
    }

    /// Ends the driver: closes its stdin (it then closes the browser), waits up to `grace`, and
    /// kills whatever is left of its process group.
    pub fn stop(&mut self, grace: Duration) {
        // Once the group is gone its id may be reused: signal it only once.
        if std::mem::replace(&mut self.stopped, true) {
            return;
        }
        drop(self.stdin.take());
        let deadline = Instant::now() + grace;
        while Instant::now() < deadline {
            match self.child.try_wait() {
                Ok(Some(_)) | Err(_) => break,
                Ok(None) => thread::sleep(Duration::from_millis(20)),
            }
        }
        // The group id is the driver's pid (process_group(0)); Chromium's processes stay in it
        // even after the driver exits, and the id cannot be reused while any of them lives.
        if let Ok(pgid) = i32::try_from(self.child.id()) {
            // SAFETY: killpg only sends a signal; a group that is already gone gives ESRCH.
            unsafe {
                libc::killpg(pgid, libc::SIGKILL);
            }
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        self.stop(Duration::from_secs(5));
    }
}
