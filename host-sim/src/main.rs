//! The `foxhunt` command: its subcommands and their dispatch. Every subcommand's options and
//! work live in `foxhunt_sim::commands`.

use clap::{Parser, Subcommand};
use foxhunt_sim::commands;
use foxhunt_sim::outputs::terminal::{Out, note};
use std::process::ExitCode;

/// Find radio transmitters from bearings: fixes of recorded and live drives, indoor RSSI
/// tracking, and benchmarks of every method against the Cramér-Rao bound.
#[derive(Parser)]
#[command(name = "foxhunt", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Locate the emitter of a drive (NMEA GPS and heading sentences with $PFOXB, Agrelo or
    /// KrakenSDR bearings).
    ///
    /// With no CAPTURE, locates the bundled sample drive (made by `foxhunt simulate
    /// --scenario aoa-drive`). `-` reads standard input live: a fix line per update as the
    /// bytes arrive, as with --baud. --gpsd takes positions and heading from a running gpsd
    /// beside such a live line; --kraken polls a KrakenSDR's web page instead of a line. Each
    /// update (and the report of a recorded drive) ends with the advice: where to drive next
    /// (a heading, or with --roads FILE the next road turn) and why ("widen the angle", "get
    /// closer", "drive a calibration leg"), or "good enough: stop" once the stop rule holds
    /// (--target-cep50-m, default 100 m). Maps are written only where asked (--maps PREFIX, or
    /// --geojson/--kml/--svg), never onto an input. Where the bearings cross but leave the
    /// range open, the answer is a region (a line of bearing from the observers, its
    /// half-width and range interval), printed and drawn, but no fix. Exit status: 0 with a
    /// fix, 1 when the capture gives none (the message says why; a region only is no fix), 2
    /// on a usage error.
    ///
    /// Examples:
    ///   foxhunt locate                                  # the bundled sample drive
    ///   foxhunt locate --maps foxhunt-sample            # ...and its three maps
    ///   foxhunt locate drive.nmea --json
    ///   foxhunt locate drive.nmea --method sir-robust --geojson fix.geojson
    ///   cat /dev/ttyUSB0 | foxhunt locate - --sigma-deg 2
    ///   foxhunt locate /dev/ttyUSB0 --baud 4800 --quiet-exit 30
    ///   foxhunt locate /dev/ttyUSB0 --baud 4800 --gpsd       # positions, heading from gpsd
    ///   foxhunt locate --kraken http://192.168.1.20:8081     # a KrakenSDR on the network
    ///   foxhunt locate /dev/ttyUSB0 --baud 4800 --roads area.osm.pbf --target-cep50-m 50
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Locate(Box<commands::locate::Args>),
    /// Track an emitter that moves: bearings of any station and format, RSSI of known anchors.
    ///
    /// Every channel of the captures is tracked with a particle filter (a still and a moving
    /// model, each DF unit's offset learned): per update, position, velocity, 95 % ellipse and
    /// P(moving). A channel one DF station alone hears (bearings, no RSSI) is not: from one
    /// station a moving emitter's range is not observable (`locate` fixes a still one). RSSI
    /// comes from a ZigBee coordinator's AF_INCOMING_MSG frames and needs the anchors file
    /// (TOML: each anchor's short address and position, the room, path loss and noise).
    /// Prints CSV (or --json); --geojson, --csv and --svg write files. Live (-, --baud,
    /// --kraken, --mqtt): one line per update as the bearings arrive (a JSON object with
    /// --json). Exit status: 0 with a track, 1 when there is none (the message says why), 2
    /// on a usage error.
    ///
    /// Examples:
    ///   foxhunt track drone.nmea --json
    ///   foxhunt track drone.xml --stations drone.stations.toml
    ///   cat /dev/ttyUSB0 | foxhunt track - --json
    ///   foxhunt track --mqtt mqtt://127.0.0.1:1883/foxhunt --quiet-exit 30
    ///   foxhunt track serial-bridge/captures/rssi-sim.znp --anchors serial-bridge/captures/rssi-sim.anchors.toml
    ///   foxhunt track node.cap --anchors lab.toml --json --svg track.svg
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Track(commands::track::Args),
    /// Every decoded frame of a capture as a JSON line, then the counters.
    ///
    /// Kinds: positions gga, rmc, gll, gns; headings vtg, hdt, ths, hdg, hdm; bearings pfoxb,
    /// agrelo, kraken_csv, kraken_xml; a DF unit's own sentences pfoxf (fix), pfoxs (status),
    /// pfoxl (link), pfoxr (ready), pfoxa (acknowledgement) and pfoxc (command); ZigBee
    /// af_incoming_msg, mt (other MT frames); nmea (any other sentence). The last line,
    /// `counters`, has the demultiplexer's counters and `kinds`, the lines of each kind.
    ///
    /// Example:
    ///   foxhunt frames drive.nmea | grep pfoxb
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Frames(commands::frames::Args),
    /// Write a capture as the radios would send it (a drive in a DF unit's format; for
    /// rssi-sim and rssi-lab, AF_INCOMING_MSG frames and an anchors file).
    ///
    /// Drive formats (--format): pfoxb (GGA + RMC + $PFOXB true bearings, the default),
    /// agrelo (GGA + RMC + HDT + %BBB/Q relative bearings), kraken-csv and kraken-xml
    /// (KrakenSDR records with their own position and heading, no NMEA). The route's first
    /// point lies at --origin (default 47.0,8.0) and is the capture's local origin. The GPS
    /// reports each route point at a whole second, the PFOXB unit half a second later; a drive
    /// past midnight rolls the date.
    ///
    /// Examples:
    ///   foxhunt simulate --scenario aoa-drive --out drive.nmea
    ///   foxhunt simulate --scenario aoa-drive --format kraken-csv --out mydata.csv
    ///   foxhunt simulate --scenario aoa-drive --bias-deg 4 --wild 0.1 --out biased.nmea
    ///   foxhunt simulate --scenario-file my.toml --origin 53.35,-6.26 --out my.nmea
    ///   foxhunt simulate --scenario rssi-sim --out lab.znp --anchors-out lab.toml
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Simulate(commands::simulate::Args),
    /// Monte Carlo benchmark of every method on a scenario, against the CRLB (or PCRB).
    ///
    /// Bearing scenarios: aoa-afsa, aoa-firefly, aoa-pf-vs-kf, aoa-drive, aoa-afsa-wild.
    /// Tracking scenarios: rssi-sim (N = 50, 100, 200), rssi-lab, ungm.
    /// Progress goes to stderr (a bar on a terminal, a line every 5 s otherwise).
    ///
    /// Examples:
    ///   foxhunt bench                              # aoa-afsa, 100 seeded runs
    ///   foxhunt bench --scenario all --markdown    # every canonical scenario, the book's table
    ///   foxhunt bench --scenario rssi-sim --runs 20 --particles 80
    ///   foxhunt bench --scenario-file my.toml --json
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Bench(commands::bench::Args),
    /// Speed: the bootstrap SIR against the same filter in numpy (filterpy), how every
    /// filter's step time grows with N (100 to 100 000), and with --scale `locate` on large
    /// captures. Single thread; markdown tables.
    ///
    /// Installs the peer (numpy, scipy and filterpy at the versions pinned in
    /// host-sim/benches/peer-requirements.txt) from PyPI into target/peer-venv on first use.
    /// Example: foxhunt perf --runs 20 --scale
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Perf(commands::perf::Args),
    /// A live map in the browser: route, bearings, every emitter and other source with its
    /// ellipse, the suggested move and the CEP50 history, pushed as the input is decoded.
    ///
    /// Replays capture files (paced) or reads standard input (`-`) as it arrives. Roads from an
    /// OpenStreetMap extract (--roads, .osm.pbf or OSM XML) are the basemap, so it works
    /// offline, and make the advice a road turn; online tiles are optional (--tiles).
    ///
    /// Examples:
    ///   foxhunt serve serial-bridge/captures/aoa-drive.nmea      # then open http://127.0.0.1:8080/
    ///   cat /dev/ttyUSB0 | foxhunt serve - --roads area.osm.pbf
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Serve(commands::serve::Args),
    /// Send a DF station's bearings to an MQTT broker, for `foxhunt locate --mqtt` to fuse.
    ///
    /// Reads any source `locate` reads (capture files, - for standard input, a serial device
    /// with --baud, --kraken URL; a vehicle's positions and heading from gpsd with --gpsd)
    /// through the same decoder and sends each bearing as one JSON message (station, time_ms
    /// UTC, lat, lon, bearing_deg true, sigma_deg, freq_mhz, quality, kind) to
    /// PREFIX/bearings/CHANNEL/STATION at QoS 1 on a persistent session.
    /// While the broker is away the bearings wait (--buffer), and what it had not acknowledged
    /// is sent again when it is back. --pace replays a recorded capture in (scaled) real time.
    /// Exit status: 0 when the broker acknowledged every bearing, 1 when it could not be
    /// reached or some were not acknowledged within --linger, 2 on a usage error.
    ///
    /// Examples:
    ///   foxhunt publish north.xml --mqtt mqtt://broker:1883/net
    ///   foxhunt publish drive.nmea --station car-1 --pace 1 --mqtt mqtt://127.0.0.1/net
    ///   foxhunt publish --kraken http://192.168.1.20:8081 --mqtt mqtt://broker/net
    ///   foxhunt publish /dev/ttyUSB0 --baud 4800 --gpsd --station car-1 --mqtt mqtt://broker/net
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Publish(commands::publish::Args),
    /// What a run's history holds (`foxhunt locate --db FILE`): its bearings, stations,
    /// channels, period and fixes, and with --csv or --geojson all of them exported.
    ///
    /// The file is only read, also while a worker writes it. --since and --until (RFC 3339 or
    /// ms since 1970 UTC) keep a period. Exit status: 0, 1 when the file cannot be read
    /// (locked by another program), 2 on a usage error or a file that is not a foxhunt history
    /// of this schema.
    ///
    /// Examples:
    ///   foxhunt history net.db
    ///   foxhunt history net.db --csv net --geojson net.geojson --since 2026-06-01T10:00:00Z
    #[command(verbatim_doc_comment)]
    History(commands::history::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let mut out = Out::new();
    let result = match &cli.command {
        Command::Locate(a) => commands::locate::run(a, &mut out),
        Command::Track(a) => commands::track::run(a, &mut out),
        Command::Frames(a) => commands::frames::run(a, &mut out),
        Command::Simulate(a) => commands::simulate::run(a),
        Command::Bench(a) => commands::bench::run(a, &mut out),
        Command::Perf(a) => commands::perf::run(a, &mut out),
        Command::Serve(a) => commands::serve::run(a),
        Command::Publish(a) => commands::publish::run(a),
        Command::History(a) => commands::history::run(a, &mut out),
    }
    .and_then(|()| out.flush());
    // What went wrong decides the status (`Stop::status`: 1 no result, 2 usage; clap's own
    // usage errors exit 2 before this), on one line that names the problem.
    let stop = match result {
        Ok(()) => return ExitCode::SUCCESS,
        Err(stop) => stop,
    };
    if let Some(e) = stop.message() {
        note(&format!("foxhunt: {}", e.replace('\n', " ")));
    }
    ExitCode::from(stop.status())
}
