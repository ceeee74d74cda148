//! Each DF source's bearing noise from its bearings' scatter about the track.
//!
//! A track weighs each bearing by the noise it is given: `--sigma`, a stations file's
//! `noise_deg`, else the record's own, which for a PFOXB or a KrakenSDR record is the
//! bridge's 1 degree, not anything the unit measured. A unit noisier than that would get
//! ellipses too small (a 3 degree unit tracked at 1 degree: 48 % coverage,
//! docs/src/tracking.md). So where no one stated the noise it is estimated, as `locate`
//! estimates it: each source's residuals about the track, over the noise its records give and
//! less their median (the source's offset, which the track holds too), have a robust scale
//! (1.4826 median absolute deviations: wild bearings do not count). The filtered track has
//! seen each bearing, yet on the moving scenarios a noise given right scatters 0.86-1.23
//! times (600 bearings a source), so the scale is taken as it is.
//!
//! Only ever widened: a unit quieter than its records say keeps their noise (its ellipses a
//! little wide, rather than narrowed by the estimate's luck). A recording is tracked again
//! with the widened noise ([`track_estimating`]); a live line widens a source's noise from the
//! update after its scatter is known ([`LiveScatter`]).
//!
//! A scatter alone does not show an error that persists over many reports, as an indoor
//! array's compression toward boresight does: a source of which nothing at all is stated
//! whose noise passes [`ARRAY_ABOVE`], which no outdoor array reaches, is tracked as an indoor
//! array (the recording once more, a live channel's track from the start again;
//! docs/src/tracking.md, "An indoor array no one stated").

use crate::track::moving::{Settings, TrackPoint, TrackRun, Update, track};
use foxhunt_core::Error;
use foxhunt_core::fix::device::{DeviceClass, TrackTraits};
use foxhunt_core::fix::observation::Observation;
use foxhunt_core::model::bearing::wrap;
use std::collections::{BTreeMap, VecDeque};

/// Beyond this noise, radians, a unit scatters as no working outdoor array does (the
/// ceiling of their device classes, `core/src/fix/device.rs`) and as an indoor array's
/// reports do (10-16 degrees): a source of which nothing is stated is then tracked as an
/// indoor array ([`Unstated::Everything`]).
pub const ARRAY_ABOVE: f32 = 10.0 * std::f32::consts::PI / 180.0;

/// How a track takes an indoor array's reports ([`DeviceClass::track`]).
const ARRAY: TrackTraits = DeviceClass::IndoorAoa.track();

/// What a note on a source's estimated noise adds when the track took the source as an
/// indoor array: taken as independent, such reports held a simulated walker 50-68 % of the
/// time, as an array's 95-98 % (docs/src/tracking.md).
pub fn array_note(array: bool) -> &'static str {
    if array {
        "; a scatter no outdoor array shows: taken as an indoor angle-of-arrival array's \
         (each report at twice it, a 7.2 deg offset prior, offsets forgetting in 10 s); a \
         stations file's antenna states its class"
    } else {
        ""
    }
}

/// `s` with sources `arrays` (by number) taken as indoor arrays: their offset priors widened
/// to the class's, the offsets forgetting in the class's time unless `s` says otherwise.
/// (Their reports' noise is the caller's: [`report_factor`].)
pub fn as_arrays(s: &mut Settings, arrays: impl Iterator<Item = usize>) {
    let mut any = false;
    for k in arrays {
        any = true;
        if let (Some(prior), Some(sd)) = (s.offsets.get_mut(k), ARRAY.offset_sd) {
            prior.sd = prior.sd.max(sd);
        }
    }
    if any {
        s.memory_s = s.memory_s.or(ARRAY.memory_s);
    }
}

/// How many times its scatter an array's reports take (1 for other sources).
pub fn report_factor(array: bool) -> f32 {
    if array { ARRAY.report_sd_factor } else { 1.0 }
}

/// What no one stated of a source, and so what its track learns from its bearings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unstated {
    /// Nothing to learn: its noise is stated (`--sigma`, the stations file, its class).
    Nothing,
    /// Its noise (its class or its offset prior is stated): estimated.
    Noise,
    /// Its noise, its class and its offset prior: the noise estimated, and a noise beyond
    /// [`ARRAY_ABOVE`] tracks it as an indoor array ([`DeviceClass::IndoorAoa`]'s
    /// [`track`](DeviceClass::track) traits), the one kind of unit that scatters so.
    Everything,
}

impl Unstated {
    /// Whether the source's noise is estimated.
    pub fn noise(self) -> bool {
        self != Unstated::Nothing
    }
}

/// Bearings fewer than this from a source say nothing of its scatter.
pub const MIN_BEARINGS: usize = 30;
/// A source's noise is widened when its bearings scatter by more than this many times the
/// noise given them. A noise given right scatters 0.86-1.23 times (means 0.97-1.01), so
/// such a unit is now and then widened by up to a quarter: its ellipses a little wide.
pub const WIDEN_ABOVE: f32 = 1.1;
/// A stated noise (`--sigma`, a stations file's) whose bearings scatter about the track by
/// more than this many times is said to be too small (it is kept): room above the 0.86-1.23
/// of a noise stated right for heavy tails and an error that changes with direction.
pub const STATED_TOO_SMALL: f32 = 1.5;
/// Tracks of a recording at most: the first with the records' noise, then until no source's
/// estimate moves by more than [`SETTLED`] (the filter follows bearings it is told are
/// good, so the first track's scatter is short of the unit's).
const PASSES: usize = 4;
/// An estimate that moves by less than this share from one track to the next has settled.
const SETTLED: f32 = 0.05;
/// Residuals a live source keeps: its last this many bearings give its scale (bounded memory
/// on a line that never ends; a few minutes of a 1 Hz unit).
pub const LIVE_WINDOW: usize = 300;

/// Bearing `o`'s residual about position `p`, in the bearing's own sds.
fn residual(o: &Observation, p: [f32; 2]) -> f32 {
    let b = &o.bearing;
    let seen = (p[1] - b.vehicle[1]).atan2(p[0] - b.vehicle[0]);
    wrap(b.theta - seen) / b.sigma
}

/// The robust scale of `z` about its median (1.4826 median absolute deviations), if there
/// are [`MIN_BEARINGS`] of them.
fn robust_scale(mut z: Vec<f32>) -> Option<f32> {
    if z.len() < MIN_BEARINGS {
        return None;
    }
    let median = |v: &mut Vec<f32>| {
        v.sort_by(f32::total_cmp);
        v[v.len() / 2]
    };
    let centre = median(&mut z);
    let mut dev: Vec<f32> = z.iter().map(|x| (x - centre).abs()).collect();
    Some(1.4826 * median(&mut dev))
}

/// One source's bearings about a track.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SourceNoise {
    /// The source's number in the updates.
    pub source: u16,
    /// The noise its bearings were given (their median), radians.
    pub given: f32,
    /// Their scatter about the track in those sds (1 where the noise given is right).
    pub scatter: f32,
    /// How many times `given` the track took (1: as given).
    pub widened: f32,
    /// Tracked as an indoor array, its class unstated ([`Unstated::Everything`]).
    pub array: bool,
}

impl SourceNoise {
    /// The noise the track took, radians.
    pub fn tracked(&self) -> f32 {
        self.given * self.widened
    }

    /// How many times `given` its scatter was taken as (`widened` less an array's factor).
    pub fn shown(&self) -> f32 {
        self.widened / report_factor(self.array)
    }
}

/// Each source's bearings in `updates` about the track `points` (one point an update), for
/// the sources with [`MIN_BEARINGS`] or more, by source number (as given: none widened).
pub fn scatter(updates: &[Update], points: &[TrackPoint]) -> Vec<SourceNoise> {
    let mut by: BTreeMap<u16, (Vec<f32>, Vec<f32>)> = BTreeMap::new();
    for (u, p) in updates.iter().zip(points).filter(|(u, p)| u.t_s == p.t_s) {
        for o in u.epoch.bearings() {
            let e = by.entry(o.station).or_default();
            e.0.push(residual(o, p.position));
            e.1.push(o.bearing.sigma);
        }
    }
    by.into_iter()
        .filter_map(|(source, (z, mut given))| {
            let scatter = robust_scale(z)?;
            given.sort_by(f32::total_cmp);
            Some(SourceNoise {
                source,
                given: given[given.len() / 2],
                scatter,
                widened: 1.0,
                array: false,
            })
        })
        .collect()
}

/// `updates` with each bearing's noise `widened[source]` times (1 beyond the list).
fn widen(updates: &[Update], widened: &[f32]) -> Vec<Update> {
    updates
        .iter()
        .map(|u| {
            let mut u = *u;
            for o in u.epoch.bearings_mut() {
                o.bearing.sigma *= widened.get(usize::from(o.station)).copied().unwrap_or(1.0);
            }
            u
        })
        .collect()
}

/// Track `updates` as `s` says, each source whose noise is not stated (`unstated[source]`)
/// widened to its bearings' scatter about the track where that is more than
/// [`WIDEN_ABOVE`] times the noise given ([the module](self)), then, if the estimate makes a
/// source of which nothing is stated an indoor array ([`Unstated::Everything`]), tracked
/// once more with the array's traits: the track and each source's noise (sources with
/// [`MIN_BEARINGS`] or more). The run's evaluations are every pass's.
pub fn track_estimating(
    updates: &[Update],
    s: &Settings,
    unstated: &[Unstated],
) -> Result<(TrackRun, Vec<SourceNoise>), Error> {
    let mut run = track(updates, s)?;
    let mut noise = scatter(updates, &run.points);
    let of = |k: u16| {
        unstated
            .get(usize::from(k))
            .copied()
            .unwrap_or(Unstated::Nothing)
    };
    let mut widened = vec![1.0f32; unstated.len()];
    if noise
        .iter()
        .any(|n| of(n.source).noise() && n.scatter > WIDEN_ABOVE)
    {
        for _ in 1..PASSES {
            let mut moved = false;
            for n in noise.iter().filter(|n| of(n.source).noise()) {
                let k = usize::from(n.source);
                let next = n.scatter.max(1.0);
                moved |= (next / widened[k] - 1.0).abs() > SETTLED;
                widened[k] = next;
            }
            if !moved {
                break;
            }
            let spent = run.evaluations;
            run = track(&widen(updates, &widened), s)?;
            run.evaluations += spent;
            noise = scatter(updates, &run.points);
        }
    }
    let arrays: Vec<usize> = noise
        .iter()
        .map(|n| (n, usize::from(n.source)))
        .filter(|(n, k)| {
            let tracked = n.given * widened.get(*k).unwrap_or(&1.0);
            of(n.source) == Unstated::Everything && tracked > ARRAY_ABOVE
        })
        .map(|(_, k)| k)
        .collect();
    if !arrays.is_empty() {
        let mut s = s.clone();
        as_arrays(&mut s, arrays.iter().copied());
        for k in &arrays {
            widened[*k] *= report_factor(true);
        }
        let spent = run.evaluations;
        run = track(&widen(updates, &widened), &s)?;
        run.evaluations += spent;
        noise = scatter(updates, &run.points);
    }
    for n in noise.iter_mut() {
        n.widened = widened.get(usize::from(n.source)).copied().unwrap_or(1.0);
        n.array = arrays.contains(&usize::from(n.source));
    }
    Ok((run, noise))
}

/// A live channel's sources' scatter about its track: each source's last [`LIVE_WINDOW`]
/// residuals, the noise its next bearings take, and which it takes as indoor arrays.
#[derive(Debug, Clone, Default)]
pub struct LiveScatter {
    residuals: Vec<VecDeque<f32>>,
    /// How many times its records' noise each source's scatter is (1: as given).
    shown: Vec<f32>,
    /// Each source's records' noise, its last bearing's, radians.
    given: Vec<f32>,
    /// Whether each is taken as an indoor array.
    arrays: Vec<bool>,
}

impl LiveScatter {
    /// Widen the bearings of `u` of the sources whose noise is estimated.
    pub fn widen(&self, u: &mut Update) {
        for o in u.epoch.bearings_mut() {
            o.bearing.sigma *= self.widened(o.station);
        }
    }

    /// How many times its records' noise source `k`'s bearings take (1: as given).
    pub fn widened(&self, k: u16) -> f32 {
        self.shown(k) * report_factor(self.array(k))
    }

    /// How many times its records' noise source `k`'s bearings scatter, as far as it is
    /// taken (1: as given, or too few bearings yet).
    pub fn shown(&self, k: u16) -> f32 {
        self.shown.get(usize::from(k)).copied().unwrap_or(1.0)
    }

    /// Whether source `k` is taken as an indoor array.
    pub fn array(&self, k: u16) -> bool {
        self.arrays.get(usize::from(k)).copied().unwrap_or(false)
    }

    /// The noise source `k`'s bearings now take, radians (0 before it was heard).
    pub fn tracked(&self, k: u16) -> f32 {
        self.given.get(usize::from(k)).copied().unwrap_or(0.0) * self.widened(k)
    }

    /// Learn from update `u` (as given, before [`widen`](Self::widen)) and its point `p`:
    /// each source's scale whose noise is estimated (`unstated[source]`), widened once it
    /// passes [`WIDEN_ABOVE`]; whether a source became an indoor array ([`ARRAY_ABOVE`]).
    pub fn learn(&mut self, u: &Update, p: &TrackPoint, unstated: &[Unstated]) -> bool {
        let of = |k: u16| {
            unstated
                .get(usize::from(k))
                .copied()
                .unwrap_or(Unstated::Nothing)
        };
        let mut became = false;
        for o in u.epoch.bearings().iter().filter(|o| of(o.station).noise()) {
            let k = usize::from(o.station);
            if self.residuals.len() <= k {
                self.residuals.resize_with(k + 1, VecDeque::new);
                self.shown.resize(k + 1, 1.0);
                self.given.resize(k + 1, 0.0);
                self.arrays.resize(k + 1, false);
            }
            self.given[k] = o.bearing.sigma;
            let r = &mut self.residuals[k];
            if r.len() == LIVE_WINDOW {
                r.pop_front();
            }
            r.push_back(residual(o, p.position));
            if let Some(z) = robust_scale(r.iter().copied().collect()) {
                let w = &mut self.shown[k];
                if *w > 1.0 || z > WIDEN_ABOVE {
                    *w = z.max(1.0);
                }
            }
            let noise = self.given[k] * self.shown[k];
            if of(o.station) == Unstated::Everything && !self.arrays[k] && noise > ARRAY_ABOVE {
                self.arrays[k] = true;
                became = true;
            }
        }
        became
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::updates::bearing_updates;
    use foxhunt_core::model::bearing::Bearing;
    use foxhunt_core::track::{Layout, Motion};
    use rand_core::SeedableRng;

    /// Four masts round an emitter crossing between them at 10 m/s, 240 s at 1 Hz, mast i's
    /// bearings `noise_deg[i]` off at random but stated as 1 degree.
    fn masts(noise_deg: [f32; 4]) -> Vec<Update> {
        let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(7);
        let masts = [
            [0.0f32, 0.0],
            [4000.0, 0.0],
            [4000.0, 4000.0],
            [0.0, 4000.0],
        ];
        let mut obs = Vec::new();
        for k in 0..240 {
            let t = k as f32;
            let p = [1000.0 + 10.0 * t, 1500.0 + 2.0 * t];
            for (i, m) in masts.iter().enumerate() {
                let truth = (p[1] - m[1]).atan2(p[0] - m[0]);
                let e = noise_deg[i].to_radians() * foxhunt_core::random::normal(&mut rng);
                let bearing = Bearing {
                    vehicle: *m,
                    theta: wrap(truth + e),
                    sigma: 1f32.to_radians(),
                };
                let mut o = Observation::new(bearing, t + 0.01 * i as f32);
                o.station = i as u16;
                obs.push(o);
            }
        }
        bearing_updates(&obs)
    }

    fn settings() -> Settings {
        let mut s = Settings::new(
            Layout {
                sources: 4,
                rssi: false,
            },
            Motion::OUTDOOR,
        );
        s.particles = 1000;
        s.offsets = vec![foxhunt_core::fix::bias::BiasPrior::default(); 4];
        s
    }

    /// The first three masts' noise estimated, the fourth's stated.
    const THREE_FREE: [Unstated; 4] = [
        Unstated::Noise,
        Unstated::Noise,
        Unstated::Noise,
        Unstated::Nothing,
    ];

    fn show(noise: &[SourceNoise]) {
        for n in noise {
            println!(
                "source {}: scatter {:.2}, tracked {:.2} deg, array {}",
                n.source,
                n.scatter,
                n.tracked().to_degrees(),
                n.array
            );
        }
    }

    #[test]
    fn a_unit_noisier_than_stated_is_widened_to_its_noise_and_one_as_stated_is_not() {
        let updates = masts([3.0, 3.0, 3.0, 1.0]);
        let (_, noise) = track_estimating(&updates, &settings(), &THREE_FREE).expect("a track");
        show(&noise);
        assert_eq!(noise.len(), 4);
        // The estimate of a 3 degree unit from 240 bearings: its own spread is about 7 %, the
        // filtered track's residuals a little short of the noise; 2.4-3.6 leaves both room.
        for n in &noise[..3] {
            assert!((2.4..3.6).contains(&n.tracked().to_degrees()), "{n:?}");
        }
        assert_eq!(noise[3].widened, 1.0, "stated right: kept");
        // A noise given right scatters 0.86-1.23 times ([`WIDEN_ABOVE`]); these four are
        // widened up to 1.24 (measured): 1.3 leaves room, and a 3 degree unit's 3x fails it.
        let (_, right) =
            track_estimating(&masts([1.0; 4]), &settings(), &[Unstated::Noise; 4]).unwrap();
        assert!(right.iter().all(|n| n.widened < 1.3), "{right:?}");
    }

    #[test]
    fn a_source_of_which_nothing_is_stated_scattering_as_an_indoor_array_is_tracked_as_one() {
        // Three masts scattering 12 degrees, one 1; of the first nothing is stated, of the
        // second its class (its noise estimated), of the fourth nothing.
        let updates = masts([12.0, 12.0, 12.0, 1.0]);
        let unstated = [
            Unstated::Everything,
            Unstated::Noise,
            Unstated::Everything,
            Unstated::Everything,
        ];
        let (run, noise) = track_estimating(&updates, &settings(), &unstated).expect("a track");
        show(&noise);
        let arrays: Vec<bool> = noise.iter().map(|n| n.array).collect();
        assert_eq!(arrays, [true, false, true, false]);
        // An array takes twice its scatter; the others their scatter (a 12 degree estimate
        // from 240 bearings is within a fifth).
        for n in &noise[..3] {
            let shown = n.given * n.shown();
            assert!((9.6..14.4).contains(&shown.to_degrees()), "{n:?}");
            assert_eq!(n.tracked(), shown * report_factor(n.array));
        }
        // The widened passes and the array's: more than one track's evaluations.
        assert!(run.evaluations > 1);
        let mut s = settings();
        as_arrays(&mut s, [0, 2].into_iter());
        assert_eq!(s.memory_s, ARRAY.memory_s);
        assert!(s.offsets[0].sd >= 7.2f32.to_radians() - 1e-6);
        assert_eq!(s.offsets[1], settings().offsets[1]);
        // Told to take nothing as arrays, no array.
        let (_, noise) = track_estimating(&updates, &settings(), &[Unstated::Noise; 4]).unwrap();
        assert!(noise.iter().all(|n| !n.array));
    }

    #[test]
    fn a_live_source_is_widened_once_enough_bearings_scatter_beyond_the_stated_noise() {
        let updates = masts([3.0, 3.0, 3.0, 1.0]);
        let run = track(&updates, &settings()).unwrap();
        let mut live = LiveScatter::default();
        let free = THREE_FREE;
        for (u, p) in updates.iter().zip(&run.points).take(MIN_BEARINGS - 1) {
            live.learn(u, p, &free);
        }
        assert_eq!(live.widened(0), 1.0, "too few bearings yet");
        for (u, p) in updates.iter().zip(&run.points).skip(MIN_BEARINGS - 1) {
            live.learn(u, p, &free);
        }
        println!("widened {:.2} {:.2}", live.widened(0), live.widened(3));
        assert!(live.widened(0) > 1.5 && live.widened(3) == 1.0);
        let mut u = updates[0];
        live.widen(&mut u);
        let sigma = u.epoch.bearings()[0].bearing.sigma;
        assert!((sigma / 1f32.to_radians() - live.widened(0)).abs() < 1e-4);
        assert!(live.residuals.iter().all(|r| r.len() <= LIVE_WINDOW));
        assert!(!live.array(0), "its class stated: no array");
        // Of which nothing is stated, a 12 degree unit becomes an array once, and its channel
        // is told so (about a track that knew its noise).
        let updates = masts([12.0, 1.0, 1.0, 1.0]);
        let run = track(&widen(&updates, &[12.0, 1.0, 1.0, 1.0]), &settings()).unwrap();
        let mut live = LiveScatter::default();
        let became: Vec<usize> = updates
            .iter()
            .zip(&run.points)
            .enumerate()
            .filter(|(_, (u, p))| live.learn(u, p, &[Unstated::Everything; 4]))
            .map(|(k, _)| k)
            .collect();
        println!(
            "array from update {became:?}: {:.1} deg",
            live.tracked(0).to_degrees()
        );
        assert_eq!(became.len(), 1, "{became:?}");
        assert!(live.array(0) && !live.array(1));
        assert_eq!(live.widened(0), 2.0 * live.shown(0));
    }
}
