//! `device identify` across Q 50–2000, resonances over the sweep's span,
//! loaded and unloaded (issue 41 §8): every point's voltage planned from
//! the response measured so far (eqs. I1–I4 of docs/transducers.md), so no
//! mode is rung toward the lift-off limit, whatever its Q up to
//! `identify::Q_MAX`. The plant's *true* normal excursion is watched at every
//! sample (`Plant::excursion_limit_m`, `samples_above`), not the device's
//! measurement of it.

use std::io;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use board::device::DriveSetting;
use board::protocol::{Request, Response};
use device_host::client::Client;
use device_host::identify::{identify, Channels, IdentifyOptions};
use device_host::link::Link;
use device_host::transducers::TransducerSpec;
use device_host::virtual_device::{PlantSpec, VirtualDevice};

/// What the plant's true normal motion did: the largest excursion, m.
#[derive(Default, Debug, Clone, Copy)]
struct Watch {
    peak_m: f64,
    above: u64,
    /// Device time run, s.
    device_s: f64,
}

struct WatchedSim {
    dev: VirtualDevice,
    /// The device's clock: when the link opened, plus the time it ran.
    epoch: Instant,
    ran: Duration,
    pending: Vec<u8>,
    watch: Arc<Mutex<Watch>>,
}

impl Link for WatchedSim {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let out = self.dev.receive(bytes);
        self.pending.extend(out);
        Ok(())
    }
    /// Paced as a real device is, on the device's own clock
    /// ([`Link::now`]): a wait of `timeout` with nothing pending runs the
    /// device for `timeout` of its time (whole 64-sample half-buffers,
    /// stopping at the first byte it sends), whatever the host's speed.
    /// (Before, the device ran 1 ms steps until the *host's* clock passed
    /// the client's deadline, so how far it ran between two polls followed
    /// the host's load, and so did the sweep's reactions.)
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        if self.pending.is_empty() {
            let half = 64usize;
            let dt = half as f64 / self.dev.sample_rate();
            let samples = (timeout.as_secs_f64() * self.dev.sample_rate()).ceil() as usize;
            for _ in 0..samples.div_ceil(half).max(1) {
                let t = self.dev.advance(half);
                self.ran += Duration::from_secs_f64(dt);
                self.pending.extend(t);
                let p = self.dev.plant();
                let mut w = self.watch.lock().unwrap();
                w.peak_m = w.peak_m.max(p.peak_excursion_m);
                w.above = p.samples_above;
                w.device_s = self.ran.as_secs_f64();
                if !self.pending.is_empty() {
                    break;
                }
            }
            if self.pending.is_empty() {
                return Ok(0);
            }
        }
        let n = self.pending.len().min(buf.len());
        buf[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        Ok(n)
    }
    fn describe(&self) -> String {
        "watched virtual device".into()
    }
    fn now(&self) -> Instant {
        self.epoch + self.ran
    }
}

/// The lift-off limit B = (1 − margin)·u_z0 of the board (margin 0.05),
/// m, at the preload u_z0 = 4 µm of the tests.
const OFFSET_M: f32 = 4e-6;

fn bound_m() -> f64 {
    f64::from((1.0 - 0.05f32) * OFFSET_M)
}

/// A virtual device with the transducers `t`, its true normal excursion
/// watched against B at every sample, the preload u_z0 = 4 µm at 20 kHz set
/// in voltage mode; its client and the watch.
fn preloaded(t: TransducerSpec) -> (Client, Arc<Mutex<Watch>>) {
    let spec = PlantSpec {
        transducers: t,
        ..PlantSpec::default()
    };
    let opts = spec
        .options(0.0, 0.0, 0.0, ["v0", "noise", "offset"])
        .unwrap();
    let mut dev = VirtualDevice::new(opts);
    dev.plant_mut().excursion_limit_m = bound_m();
    let watch = Arc::new(Mutex::new(Watch::default()));
    let link = WatchedSim {
        dev,
        epoch: Instant::now(),
        ran: Duration::ZERO,
        pending: Vec::new(),
        watch: watch.clone(),
    };
    let mut c = Client::new(Box::new(link), Duration::from_secs(2), 3);
    let d = DriveSetting {
        freq_hz: 20_000.0,
        amp_z_m: 0.0,
        amp_x_m: 0.0,
        offset_z_m: OFFSET_M,
        phase_rad: 0.0,
    };
    assert!(matches!(
        c.call(Request::SetDrive(d)).unwrap(),
        Response::Drive { .. }
    ));
    (c, watch)
}

/// One identification of channel `ch` on a plant whose `ch` mode has
/// resonance `fr`, Q `q`, load `load` (`inf` for none), the other mode at
/// its default; the drive at 20 kHz on u_z0 = 4 µm. Asserts the true
/// normal excursion stayed within B at every sample, the fit within 0.5 %
/// of f_r and of the effective Q `1/(1/Q + 1/Q_load)` (the issue's
/// figure for a plant that identified before). (The fit's 95 % intervals
/// are printed, not asserted: they count the noise, not the plant's
/// departures from eq. 1, which reach 0.14 % in Q at Q 50.)
fn identifies(ch: Channels, fr: f64, q: f64, load: f64) {
    let mut t = TransducerSpec {
        plant_load_q: Some(load),
        ..TransducerSpec::default()
    };
    if ch == Channels::Z {
        (t.plant_resonance_z, t.plant_q_z) = (Some(fr), Some(q));
    } else {
        (t.plant_resonance_x, t.plant_q_x) = (Some(fr), Some(q));
    }
    let (mut c, watch) = preloaded(t);
    let o = IdentifyOptions {
        channels: ch,
        ..IdentifyOptions::default()
    };
    let r = identify(&mut c, &o);
    let w = *watch.lock().unwrap();
    let q_eff = 1.0 / (1.0 / q + 1.0 / load);
    let case = format!("{ch:?} f_r {fr} Hz, Q {q} (loaded {q_eff:.1})");
    eprintln!(
        "{case}: true normal peak {:.3} µm of B {:.3} µm ({:.2} s of device time)",
        w.peak_m * 1e6,
        bound_m() * 1e6,
        w.device_s
    );
    assert_eq!(w.above, 0, "{case}: samples beyond B");
    assert!(w.peak_m <= bound_m(), "{case}: {w:?}");
    let id = r.unwrap_or_else(|e| panic!("{case}: {e}"));
    let fit = id.channels[0].fit.as_ref().unwrap();
    let (f, qf) = (&fit.resonance_hz, &fit.q);
    eprintln!(
        "  f_r {:.3} [{:.3}, {:.3}] Hz, Q {:.2} [{:.2}, {:.2}]",
        f.value, f.lo, f.hi, qf.value, qf.lo, qf.hi
    );
    assert!(
        (f.value / fr - 1.0).abs() <= 5e-3,
        "{case}: f_r {}",
        f.value
    );
    assert!(
        (qf.value / q_eff - 1.0).abs() <= 5e-3,
        "{case}: Q {}",
        qf.value
    );
}

/// The resonances: near the span's low edge, between two coarse points
/// (the span 19–21 kHz in 21 points steps 100 Hz), near the high edge.
const RESONANCES: [f64; 3] = [19_130.0, 20_050.0, 20_930.0];

/// Every Q over the three resonances, loaded (Q_load 2000) and unloaded in
/// turn.
fn across(q: f64) {
    for (i, fr) in RESONANCES.into_iter().enumerate() {
        let load = if i % 2 == 0 { f64::INFINITY } else { 2000.0 };
        identifies(Channels::Z, fr, q, load);
    }
}

#[test]
fn a_low_q_normal_mode_identifies_within_the_limit() {
    across(50.0);
}

#[test]
fn a_mounted_normal_mode_identifies_within_the_limit() {
    across(300.0);
}

/// The case among them: 20 050 Hz, Q 1000, unloaded — it latched
/// `measured_liftoff` when the fine pass's voltage was scaled from the
/// coarse pass alone.
#[test]
fn an_unloaded_high_q_normal_mode_identifies_within_the_limit() {
    across(1000.0);
    identifies(Channels::Z, 20_050.0, 1000.0, f64::INFINITY);
}

#[test]
fn the_highest_q_planned_for_identifies_within_the_limit() {
    across(device_host::identify::Q_MAX);
}

/// The tangential channel's bound is its largest amplitude; its plan is the
/// same. (Its excursion is not the contact's lift-off; the normal one,
/// undriven, is watched all the same.)
#[test]
fn a_high_q_tangential_mode_identifies() {
    identifies(Channels::X, 20_050.0, 1500.0, f64::INFINITY);
    identifies(Channels::X, 19_130.0, 80.0, 2000.0);
}

/// Beyond the Q the plan holds (eq. I1 with Q_MAX = 2000), the watch of
/// eq. I4 is what keeps the contact: at Q 5000 the cuts bring each point
/// back and the mode still identifies; at Q 10⁵ (τ = 1.6 s: a cut voltage
/// does not stop the ring for seconds) nothing is stored — the sweep gives
/// up by name after its cuts, or its fit refuses the undetermined Q — with
/// no fault latched, the drive stopped, and the true excursion within B all
/// along.
#[test]
fn a_mode_beyond_the_planned_q_is_cut_before_the_limit() {
    identifies(Channels::Z, 20_050.0, 5_000.0, f64::INFINITY);
    let (mut c, watch) = preloaded(TransducerSpec {
        plant_resonance_z: Some(20_050.0),
        plant_q_z: Some(1e5),
        plant_load_q: Some(f64::INFINITY),
        ..TransducerSpec::default()
    });
    let o = IdentifyOptions {
        channels: Channels::Z,
        ..IdentifyOptions::default()
    };
    // Two ways out, as the cuts and the ring's beat meet (the bench is
    // deterministic; with the poll 2-8x longer it gives up at other points):
    // the sweep gives up after its
    // cuts, or it ends and the fit refuses its record (seen: a Q its record
    // does not determine — before that verdict, Q 5e5 with a 95 % interval
    // [0.5, 6e11] and rel. RMS 2.7 % was accepted — and a singular normal
    // matrix).
    let e = match identify(&mut c, &o) {
        Err(e) => {
            let e = e.to_string();
            assert!(e.contains("kept passing 80 % of its bound"), "{e}");
            assert!(e.contains("nothing stored"), "{e}");
            e
        }
        Ok(id) => {
            // Refused by the fit's verdicts: seen QualityUndetermined and
            // SingularNormalMatrix (the record determines no mode).
            let fit = &id.channels[0].fit;
            assert!(fit.is_err(), "{fit:?}");
            assert_eq!(id.transducers, None);
            fit.as_ref().unwrap_err().to_string()
        }
    };
    let w = *watch.lock().unwrap();
    eprintln!(
        "Q 1e5: {e}; true peak {:.3} µm ({:.2} s of device time)",
        w.peak_m * 1e6,
        w.device_s
    );
    assert_eq!(w.above, 0);
    match c.call(Request::GetStatus).unwrap() {
        Response::Status(s) => assert_eq!((s.faults, s.running), (0, false), "{s:?}"),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        c.call(Request::GetTransducers).unwrap(),
        Response::Transducers(None)
    ));
}
