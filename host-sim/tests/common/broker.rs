//! A private mosquitto for the tests that need a real broker (Debian's, installed by
//! .ci/run): its own port, directory and persistence.

use std::path::PathBuf;
use std::process::{Child, Command};
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
