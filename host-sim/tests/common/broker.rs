//! A private mosquitto for the tests that need a real broker (Debian's, installed by
//! .ci/run): its own port, directory and persistence.

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::Receiver;
use std::time::{Duration, Instant};

/// One broker at a time: a port freed by one test's broker restart could otherwise be handed
/// to another test's new broker, and two brokers would fight over it.
pub fn serial() -> std::sync::MutexGuard<'static, ()> {
    static ONE: std::sync::Mutex<()> = std::sync::Mutex::new(());
    ONE.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The broker's program: on PATH, else where Debian puts it.
fn mosquitto_program() -> PathBuf {
    let on_path = std::env::var_os("PATH")
        .into_iter()
        .flat_map(|p| std::env::split_paths(&p).collect::<Vec<_>>())
        .map(|d| d.join("mosquitto"))
        .find(|p| p.is_file());
    let found = on_path.or_else(|| {
        let p = PathBuf::from("/usr/sbin/mosquitto");
        p.is_file().then_some(p)
    });
    found.expect(
        "mosquitto is not installed: these tests need a real broker (apt-get install mosquitto)",
    )
}

/// A private mosquitto: its port, directory and process.
pub struct Broker {
    /// Its loopback port.
    pub port: u16,
    /// Its directory (config, persistence, log), removed when it is dropped.
    pub dir: PathBuf,
    child: Option<Child>,
}

impl Broker {
    /// Start a broker of its own for the test `name`.
    pub fn start(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("foxhunt-mqtt-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        // mosquitto started as root drops to its own user: it must be able to write here.
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o777)).expect("chmod");
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .and_then(|l| l.local_addr())
            .expect("a free port")
            .port();
        // Persistence (saved at a clean stop, and every second) keeps the sessions and their
        // queued QoS 1 messages across a restart; no limit on a session's queue, so a worker
        // that is busy or away loses nothing.
        let conf = format!(
            "listener {port} 127.0.0.1\nallow_anonymous true\npersistence true\n\
             persistence_location {}/\nautosave_interval 1\nmax_queued_messages 0\n",
            dir.display()
        );
        std::fs::write(dir.join("mosquitto.conf"), conf).expect("config");
        let mut b = Self {
            port,
            dir,
            child: None,
        };
        b.run();
        b
    }

    /// Run the broker (again, after [`Broker::stop`]).
    pub fn run(&mut self) {
        let log = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(self.dir.join("mosquitto.log"))
            .expect("log");
        let child = Command::new(mosquitto_program())
            .arg("-c")
            .arg(self.dir.join("mosquitto.conf"))
            .stdout(log.try_clone().expect("log"))
            .stderr(log)
            .spawn()
            .expect("start mosquitto");
        self.child = Some(child);
        let start = Instant::now();
        while std::net::TcpStream::connect(("127.0.0.1", self.port)).is_err() {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "mosquitto did not listen on {}: {}",
                self.port,
                std::fs::read_to_string(self.dir.join("mosquitto.log")).unwrap_or_default()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        // Listening, and this broker (not another on the port) is the one that answered.
        let exited = self.child.as_mut().map(|c| c.try_wait());
        assert!(
            matches!(exited, Some(Ok(None))),
            "mosquitto on {} exited: {}",
            self.port,
            std::fs::read_to_string(self.dir.join("mosquitto.log")).unwrap_or_default()
        );
    }

    /// Stop the broker as a service stop does (SIGTERM: it saves its database) and wait.
    pub fn stop(&mut self) {
        if let Some(mut c) = self.child.take() {
            let _ = Command::new("kill")
                .args(["-TERM", &c.id().to_string()])
                .status();
            let _ = c.wait();
        }
    }

    /// Its URL for topics under `prefix`.
    pub fn url(&self, prefix: &str) -> String {
        format!("mqtt://127.0.0.1:{}/{prefix}", self.port)
    }
}

impl Drop for Broker {
    fn drop(&mut self) {
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// `foxhunt locate --mqtt` started: its standard output's lines, and standard error's, as
/// they come; returns once it has subscribed.
pub struct Worker {
    /// The process.
    pub child: Child,
    /// Standard output's lines.
    pub stdout: Receiver<String>,
    /// Standard error's lines after the subscription's.
    pub stderr: Receiver<String>,
    /// Standard error's lines read before the subscription's.
    early: Vec<String>,
}

impl Worker {
    /// `foxhunt locate --mqtt URL` as client `id`, ending after `quiet_s` quiet seconds.
    pub fn start(url: &str, id: &str, quiet_s: u32) -> Self {
        Self::start_with(url, id, quiet_s, &[])
    }

    /// Started with `more` arguments.
    pub fn start_with(url: &str, id: &str, quiet_s: u32, more: &[&str]) -> Self {
        Self::start_command(&["locate", "--json", "--stats"], url, id, quiet_s, more)
    }

    /// `foxhunt COMMAND --mqtt URL ...` (a `locate` or a `track`) started.
    pub fn start_command(
        command: &[&str],
        url: &str,
        id: &str,
        quiet_s: u32,
        more: &[&str],
    ) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
            .args(command)
            .args(["--mqtt", url, "--mqtt-client-id", id])
            .args(["--quiet-exit", &quiet_s.to_string()])
            .args(more)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run locate --mqtt");
        let stdout = super::lines(child.stdout.take().expect("stdout"));
        let stderr = super::lines(child.stderr.take().expect("stderr"));
        let mut w = Self {
            child,
            stdout,
            stderr,
            early: Vec::new(),
        };
        // Its first notes: what it resumed from a history, if any, and the subscription.
        let mut line = String::new();
        for _ in 0..2 {
            line = w
                .stderr
                .recv_timeout(Duration::from_secs(10))
                .expect("locate --mqtt says it subscribed");
            w.early.push(line.clone());
            if !line.starts_with("history: ") {
                break;
            }
        }
        assert!(line.contains("subscribed"), "{line}");
        w
    }

    /// Wait for the end: its last JSON line and its standard error.
    pub fn finish(self) -> (Value, Vec<String>) {
        let (mut lines, err) = self.finish_all();
        (lines.pop().expect("an update"), err)
    }

    /// Wait for the end: its exit status, standard output's lines and standard error's.
    pub fn end(mut self) -> (std::process::ExitStatus, Vec<String>, Vec<String>) {
        let status = self.child.wait().expect("wait");
        let out: Vec<String> = self.stdout.iter().collect();
        let err: Vec<String> = self.early.into_iter().chain(self.stderr.iter()).collect();
        (status, out, err)
    }

    /// Wait for the end: every JSON line and its standard error.
    pub fn finish_all(self) -> (Vec<Value>, Vec<String>) {
        let (status, out, err) = self.end();
        assert!(status.success(), "foxhunt --mqtt: {status}: {err:?}");
        let lines = out
            .iter()
            .map(|l| serde_json::from_str(l).expect("JSON"))
            .collect();
        (lines, err)
    }
}
