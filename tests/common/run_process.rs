//! `crowdtouch run` and `check-config` as processes, in an environment of their
//! own: a runtime directory the config's `path: None` socket resolves into, and a
//! system root with no installed unit. `run` is waited for until it serves its
//! socket (it started) or exits (it refused the config).

use std::net::{TcpListener, UdpSocket};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::time::{Duration, Instant};

/// How long `run` may take to start or refuse.
const START_S: u64 = 60;

/// A runtime directory and an empty system root, removed at the end.
pub struct Env {
    dir: tempfile::TempDir,
}

impl Env {
    pub fn new() -> Env {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("run")).unwrap();
        std::fs::create_dir(dir.path().join("root")).unwrap();
        Env { dir }
    }

    /// A directory for the test's files.
    pub fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Where a config with `path: None` has its socket here.
    pub fn socket(&self) -> PathBuf {
        self.dir.path().join("run/crowdtouch.sock")
    }

    /// The binary with `args`, in this environment.
    pub fn command(&self, args: &[&str]) -> Command {
        let mut c = Command::new(env!("CARGO_BIN_EXE_crowdtouch"));
        c.args(args)
            .env("XDG_RUNTIME_DIR", self.dir.path().join("run"))
            .env("CROWDTOUCH_ROOT", self.dir.path().join("root"))
            .env_remove("RUNTIME_DIRECTORY")
            .env_remove("RUST_LOG")
            .env_remove("NOTIFY_SOCKET")
            .stdin(Stdio::null());
        c
    }

    /// `check-config FILE`.
    pub fn check_config(&self, file: &Path) -> Output {
        let mut c = self.command(&["check-config"]);
        c.arg(file).output().unwrap()
    }

    /// `run --config FILE`: the daemon serving its socket, or how it refused
    /// (exit status and what it wrote).
    pub fn run(&self, file: &Path) -> Result<Running, (Option<i32>, String)> {
        let log = self.dir.path().join(format!(
            "run-{}.log",
            file.file_name().unwrap().to_string_lossy()
        ));
        let mut c = self.command(&["run", "--config"]);
        let child = c
            .arg(file)
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&log).unwrap())
            .spawn()
            .unwrap();
        let mut running = Running {
            child: Some(child),
            log,
        };
        let socket = self.socket();
        let end = Instant::now() + Duration::from_secs(START_S);
        loop {
            let child = running.child.as_mut().unwrap();
            if let Some(status) = child.try_wait().unwrap() {
                running.child = None;
                return Err((status.code(), running.log()));
            }
            if UnixStream::connect(&socket).is_ok() {
                return Ok(running);
            }
            assert!(
                Instant::now() < end,
                "run -c {} neither served {} nor exited in {START_S} s:\n{}",
                file.display(),
                socket.display(),
                running.log()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

/// A `run` process serving its socket; killed if dropped before [`Running::stop`].
pub struct Running {
    child: Option<Child>,
    log: PathBuf,
}

impl Running {
    /// Its process id.
    pub fn pid(&self) -> u32 {
        self.child.as_ref().unwrap().id()
    }

    /// What it has logged so far.
    pub fn log(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    /// Waits up to 10 s for a log line ending with `line` (the socket is served
    /// before `run` logs what it started); whether it came.
    pub fn logged(&self, line: &str) -> bool {
        let end = Instant::now() + Duration::from_secs(10);
        while !self.log().lines().any(|l| l.ends_with(line)) {
            if Instant::now() > end {
                return false;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        true
    }

    /// SIGTERM, then its exit status and its whole log.
    pub fn stop(mut self) -> (ExitStatus, String) {
        let mut child = self.child.take().unwrap();
        nix::sys::signal::kill(
            nix::unistd::Pid::from_raw(child.id() as i32),
            nix::sys::signal::Signal::SIGTERM,
        )
        .unwrap();
        let status = child.wait().unwrap();
        (status, self.log())
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// A port free a moment ago on loopback for both TCP and UDP (a WebSocket output
/// listens on TCP, a TUIO input on UDP).
pub fn free_port() -> u16 {
    loop {
        let port = TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        if UdpSocket::bind(("0.0.0.0", port)).is_ok() {
            return port;
        }
    }
}

/// `text` with the port of every `listen: "ip:port"` replaced by a free one, so
/// that a config's listeners bind whatever else runs on the machine.
pub fn free_listen_ports(text: &str) -> String {
    const KEY: &str = "listen: \"";
    let mut out = String::new();
    let mut rest = text;
    while let Some(i) = rest.find(KEY) {
        let (head, tail) = rest.split_at(i + KEY.len());
        out.push_str(head);
        let end = tail.find('"').expect("a closing quote");
        let (host, _) = tail[..end].rsplit_once(':').expect("ip:port");
        out.push_str(&format!("{host}:{}", free_port()));
        rest = &tail[end..];
    }
    out.push_str(rest);
    out
}
