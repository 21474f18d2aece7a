//! What the device commands print: one [`Report`] per answer, shown as an
//! aligned text summary with units or, with `--json`, as one flat JSON object
//! with the same keys as the model commands where the quantity is the same
//! (`mu`, `mu_over_mu0`, `v0`, `vc_forward`, `mu0`, `kz`, `uz0`, `duz`,
//! `phi_deg`, …). The keys and units of every command are in
//! `docs/device-json.md`.

use std::io::Write;

use board::device::{Contact, DriveSetting, Status};
use board::estimator::Estimate;
use board::protocol::{Applied, ControlState, ControlUpdate, Info, Prediction, SelfTest};
use model_core::regime::Regime;
use serde_json::{Map, Value};

use crate::identify::ChannelFit;

/// One answer: rows of (JSON key, text label, value, unit), in print order;
/// a row without a key is text only, one without a label JSON only.
#[derive(Default)]
pub struct Report {
    rows: Vec<(&'static str, &'static str, Value, &'static str)>,
}

pub use crate::answers::f32v;

/// The text of a standard error the estimator could not estimate (0: fewer
/// than two batches in the window).
pub const STD_ERROR_NA: &str = "n/a (fewer than 2 batches: not estimated)";

/// Degrees from radians, rounded to 1e-9 ° (the f32 phase's resolution is
/// far coarser), so that 40° does not print as 39.99999974.
fn deg(rad: f64) -> f64 {
    (rad.to_degrees() * 1e9).round() / 1e9
}

/// Degrees of an `f32` phase: the shortest decimal number of degrees that
/// converts back to the same `f32` radians (40° prints as 40, not as
/// 40.0000022 — the f32's own resolution is ≈ 4e-6° there).
fn deg32(rad: f32) -> f64 {
    let d = f64::from(rad).to_degrees();
    for p in 0..=9 {
        if let Ok(x) = format!("{d:.p$}").parse::<f64>() {
            if x.to_radians() as f32 == rad {
                return x;
            }
        }
    }
    d
}

impl Report {
    /// A row with a value and a unit ("" for none).
    pub fn row(
        mut self,
        key: &'static str,
        label: &'static str,
        v: impl Into<Value>,
        unit: &'static str,
    ) -> Self {
        self.rows.push((key, label, v.into(), unit));
        self
    }

    /// The `std_error` row of an estimate: the number in JSON (0 when the
    /// estimator had fewer than two batches to scatter, so no error was
    /// estimated), and in the text `n/a (…)` for that 0 rather than a
    /// standard error of 0.
    pub fn std_error(self, std_error: f32) -> Self {
        if std_error > 0.0 {
            self.row("std_error", "std error", f32v(std_error), "")
        } else {
            self.row("std_error", "", f32v(std_error), "")
                .row("", "std error", STD_ERROR_NA, "")
        }
    }

    /// The flat JSON object.
    pub fn json(&self) -> Value {
        Value::Object(self.json_map())
    }

    /// The flat JSON object's keys and values.
    pub fn json_map(&self) -> Map<String, Value> {
        let mut m = Map::new();
        for (k, _, v, _) in self.rows.iter().filter(|r| !r.0.is_empty()) {
            m.insert((*k).to_string(), v.clone());
        }
        m
    }

    /// The aligned text: `label  value unit`, labels padded to the longest.
    pub fn text(&self) -> String {
        let w = self.rows.iter().map(|r| r.1.len()).max().unwrap_or(0);
        let mut s = String::new();
        for (_, label, v, unit) in self.rows.iter().filter(|r| !r.1.is_empty()) {
            let value = match v {
                Value::Number(n) => n.as_f64().map_or_else(|| n.to_string(), num),
                Value::String(t) => t.clone(),
                Value::Array(a) if a.is_empty() => "none".to_string(),
                Value::Array(a) => a
                    .iter()
                    .map(|x| x.as_str().map_or_else(|| x.to_string(), str::to_string))
                    .collect::<Vec<_>>()
                    .join(", "),
                Value::Bool(b) => if *b { "yes" } else { "no" }.to_string(),
                Value::Null => "-".to_string(),
                Value::Object(_) => v.to_string(),
            };
            let line = format!("{label:<w$}  {value} {unit}");
            s.push_str(line.trim_end());
            s.push('\n');
        }
        s
    }

    /// Prints the report (text or pretty JSON) to `out`.
    pub fn print(&self, json: bool, out: &mut impl Write) -> std::io::Result<()> {
        if json {
            let s = serde_json::to_string_pretty(&self.json()).unwrap_or_default();
            writeln!(out, "{s}")
        } else {
            write!(out, "{}", self.text())
        }
    }
}

/// A number for people: integers as integers, small and large magnitudes in
/// exponent form, others in the shortest decimal form.
fn num(x: f64) -> String {
    let a = x.abs();
    if x == x.trunc() && a < 1e15 {
        format!("{}", x as i64)
    } else if a != 0.0 && !(1e-3..1e6).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// `Info`, with what answered.
pub fn info(answered_by: &str, i: &Info) -> Report {
    Report::default()
        .row("answered_by", "answered by", answered_by, "")
        .row("board", "board", board_name(&i.board), "")
        .row(
            "firmware",
            "firmware",
            format!("{}.{}.{}", i.firmware[0], i.firmware[1], i.firmware[2]),
            "",
        )
        .row("protocol", "protocol", i.protocol, "")
        .row("sample_rate_hz", "sample rate", i.sample_rate_hz, "Hz")
        .row("freq_min_hz", "frequency min", i.freq_range_hz.0, "Hz")
        .row("freq_max_hz", "frequency max", i.freq_range_hz.1, "Hz")
        .row("max_amp_x_m", "max dux", f32v(i.max_amp_x_m), "m")
        .row("max_offset_z_m", "max uz0", f32v(i.max_offset_z_m), "m")
        .row(
            "liftoff_margin",
            "lift-off margin",
            f32v(i.liftoff_margin),
            "",
        )
        .row("max_phi_deg", "max |phi|", deg32(i.max_phase_rad), "deg")
        .row("max_v0", "max |v0|", f32v(i.max_velocity_m_s), "m/s")
        .row("periods_min", "periods min", i.periods_range.0, "")
        .row("periods_max", "periods max", i.periods_range.1, "")
        .row("byte_timeout_us", "byte timeout", i.byte_timeout_us, "us")
        .row("retract_z_m", "max retract", f32v(i.retract_z_m), "m")
        .self_test(&i.self_test)
}

impl Report {
    /// A row for the JSON only (no text line).
    fn json_row(mut self, key: &'static str, v: impl Into<Value>) -> Self {
        self.rows.push((key, "", v.into(), ""));
        self
    }

    /// A line for the text only (no JSON key).
    fn text_row(mut self, label: &'static str, v: impl Into<Value>) -> Self {
        self.rows.push(("", label, v.into(), ""));
        self
    }

    /// The power-up self-test (v7): one text line (`not run`, `passed (…)`
    /// or `FAILED: names (…)`), four JSON keys (`self_test_ran`,
    /// `self_test_failed`, `hse_hz`, `sysclk_hz`).
    fn self_test(self, t: &SelfTest) -> Self {
        let hz = |f: u32| {
            if f == 0 {
                Value::Null
            } else {
                Value::from(f)
            }
        };
        self.text_row("self-test", self_test_text(t))
            .json_row("self_test_ran", self_test_names(t.ran))
            .json_row("self_test_failed", self_test_names(t.failed))
            .json_row("hse_hz", hz(t.hse_hz))
            .json_row("sysclk_hz", hz(t.sysclk_hz))
    }
}

/// The names of self-test check bits ([`board::protocol::self_test`]),
/// `0x…` for unknown bits.
pub fn self_test_names(bits: u16) -> Vec<String> {
    let mut v: Vec<String> = board::protocol::self_test::names(bits)
        .map(str::to_string)
        .collect();
    let rest = bits & !board::protocol::self_test::ALL;
    if rest != 0 {
        v.push(format!("0x{rest:x}"));
    }
    v
}

/// The self-test's text line: `not run`, `passed (HSE 8.000 MHz, SYSCLK
/// 168.0 MHz)`, `FAILED: hse_frequency (HSE 12.000 MHz, SYSCLK 168.0 MHz)`;
/// the checks that did not run are named when some did.
pub fn self_test_text(t: &SelfTest) -> String {
    if t.ran == 0 {
        return "not run".to_string();
    }
    let mut clocks = Vec::new();
    if t.hse_hz != 0 {
        clocks.push(format!("HSE {:.3} MHz", f64::from(t.hse_hz) / 1e6));
    }
    if t.sysclk_hz != 0 {
        clocks.push(format!("SYSCLK {:.1} MHz", f64::from(t.sysclk_hz) / 1e6));
    }
    let mut details = Vec::new();
    if !clocks.is_empty() {
        details.push(clocks.join(", "));
    }
    let skipped = self_test_names(board::protocol::self_test::ALL & !t.ran);
    if !skipped.is_empty() {
        details.push(format!("not run: {}", skipped.join(", ")));
    }
    let head = if t.failed == 0 {
        "passed".to_string()
    } else {
        format!("FAILED: {}", self_test_names(t.failed).join(", "))
    };
    if details.is_empty() {
        head
    } else {
        format!("{head} ({})", details.join("; "))
    }
}

/// The board name of `Info.board` (ASCII, zero-padded).
pub fn board_name(b: &[u8]) -> String {
    String::from_utf8_lossy(b)
        .trim_end_matches('\0')
        .to_string()
}

/// The accepted drive and what the DDS produces.
pub fn drive(d: &DriveSetting, a: &Applied) -> Report {
    Report::default()
        .row("freq", "freq", d.freq_hz, "Hz")
        .row("duz", "duz", f32v(d.amp_z_m), "m")
        .row("dux", "dux", f32v(d.amp_x_m), "m")
        .row("uz0", "uz0", f32v(d.offset_z_m), "m")
        .row("phi_deg", "phi", deg32(d.phase_rad), "deg")
        .row("freq_achieved", "freq achieved", a.achieved.freq_hz, "Hz")
        .row("tuning_word", "tuning word", a.achieved.tuning_word, "")
        .row("phi_achieved_deg", "phi achieved", deg(a.phase_rad), "deg")
}

/// The contact parameters.
pub fn contact(c: &Contact) -> Report {
    Report::default()
        .row("mu0", "mu0", f32v(c.mu0), "")
        .row("kz", "kz", f32v(c.kz), "N/m")
        .row("kx", "kx", f32v(c.kx), "N/m")
}

/// A command that answers `Ok`: what it did.
pub fn done(command: &'static str, what: &'static str) -> Report {
    Report::default()
        .row("command", "command", command, "")
        .row("ok", "ok", true, "")
        .row("note", "note", what, "")
}

/// The model's μ at `v0` for the current drive (keys of `fricctl mu`): at
/// v0 = 0, `mu` and `mu_over_mu0` are null and the one-sided limits are given.
pub fn prediction(v0: f64, p: &Prediction, regime: Regime) -> Report {
    let r = Report::default().row("v0", "v0", v0, "m/s");
    // With lift-off μ is continuous at rest: one value also at v0 = 0.
    let r = if v0 == 0.0 && !p.liftoff {
        r.row("mu", "mu", Value::Null, "")
            .row("mu_over_mu0", "mu/mu0", Value::Null, "")
            .row("mu_0plus_over_mu0", "mu(0+)/mu0", f32v(p.mu_over_mu0), "")
            .row(
                "mu_0minus_over_mu0",
                "mu(0-)/mu0",
                f32v(p.mu_0minus_over_mu0),
                "",
            )
    } else {
        r.row("mu", "mu", f32v(p.mu), "")
            .row("mu_over_mu0", "mu/mu0", f32v(p.mu_over_mu0), "")
    };
    r.row("vc_forward", "v_c forward", f32v(p.vc.0), "m/s")
        .row("vc_backward", "v_c backward", f32v(p.vc.1), "m/s")
        .row("regime", "regime", regime.name(), "")
        .row(
            "model",
            "model",
            if p.liftoff { "liftoff" } else { "permanent" },
            "",
        )
}

pub use crate::names::{fault_names, reason_names};

/// An estimate (`measure`, each line of `watch`).
pub fn estimate(e: &Estimate) -> Report {
    Report::default()
        .row("mu", "mu", f32v(e.mu), "")
        .std_error(e.std_error)
        .row("valid", "valid", e.valid(), "")
        .row("reasons", "reasons", reason_names(e.reasons), "")
        .row("periods", "periods", e.periods, "")
        .row("samples", "samples", e.samples, "")
        .row("saturated", "saturated", e.saturated, "")
        .row("fx_mean", "fx mean", f32v(e.fx_mean), "N")
        .row("fz_mean", "fz mean", f32v(e.fz_mean), "N")
        .row(
            "fx_h1_amplitude",
            "fx 1st harmonic",
            f32v(e.fx_h1.amplitude),
            "N",
        )
        .row(
            "fx_h1_phase_deg",
            "fx 1st harmonic phase",
            deg32(e.fx_h1.phase),
            "deg",
        )
        .row(
            "fz_h1_amplitude",
            "fz 1st harmonic",
            f32v(e.fz_h1.amplitude),
            "N",
        )
        .row(
            "fz_h1_phase_deg",
            "fz 1st harmonic phase",
            deg32(e.fz_h1.phase),
            "deg",
        )
}

/// The device settings (`device config`), as read back from the status.
pub fn config(s: &Status) -> Report {
    Report::default().row("liftoff_allowed", "lift-off allowed", s.liftoff_allowed, "")
}

/// Status and latched faults.
pub fn status(s: &Status) -> Report {
    Report::default()
        .row("running", "running", s.running, "")
        .row("settled", "settled", s.settled, "")
        .row("measuring", "measuring", s.measuring, "")
        .row("faults", "faults", fault_names(s.faults), "")
        .row("rx_overflows", "rx overflows", s.rx_overflows, "bytes")
        .row("out_duz", "output duz", f32v(s.out_amp_z_m), "m")
        .row("out_dux", "output dux", f32v(s.out_amp_x_m), "m")
        .row("out_uz0", "output uz0", f32v(s.out_offset_z_m), "m")
        .row("liftoff_allowed", "lift-off allowed", s.liftoff_allowed, "")
        .row("drive_mode", "drive mode", mode_name(s.mode), "")
        .row("frequency_hz", "frequency", f32v(s.frequency_hz), "Hz")
        .row("track", "tracking", track_name(s.options.track), "")
        .row(
            "tracking_error_hz",
            "tracking error",
            s.tracking_error_hz
                .map_or(Value::Null, |e| Value::from(f32v(e))),
            "Hz",
        )
        .row("locked", "locked", s.locked, "")
        .row("headroom", "headroom", f32v(s.options.headroom), "x steady")
        .measured(s.measured.as_ref())
        .row(
            "cpu_load_pct",
            "cpu load",
            s.cpu_load_pct.map_or(Value::Null, |p| Value::from(f32v(p))),
            "%",
        )
        .row(
            "cpu_load_max_pct",
            "cpu load max",
            s.cpu_load_max_pct
                .map_or(Value::Null, |p| Value::from(f32v(p))),
            "%",
        )
}

/// The tracked transducer's name in text and JSON: `none`, `z` or `x`.
pub fn track_name(t: board::device::Track) -> &'static str {
    match t {
        board::device::Track::None => "none",
        board::device::Track::Z => "z",
        board::device::Track::X => "x",
    }
}

/// The drive mode's name in text and JSON: `open_loop` or `displacement`.
pub fn mode_name(m: board::device::DriveMode) -> &'static str {
    match m {
        board::device::DriveMode::OpenLoop => "open_loop",
        board::device::DriveMode::Displacement => "displacement",
    }
}

impl Report {
    /// The pickups' measured motion (`Status.measured`), `null` / `-` when
    /// the device has none yet.
    pub fn measured(self, m: Option<&board::device::MeasuredDrive>) -> Self {
        let v = |f: fn(&board::device::MeasuredDrive) -> f64| -> Value {
            m.map_or(Value::Null, |m| Value::from(f(m)))
        };
        self.row(
            "amp_z_measured_m",
            "measured duz",
            v(|m| f32v(m.amp_z_m)),
            "m",
        )
        .row(
            "amp_x_measured_m",
            "measured dux",
            v(|m| f32v(m.amp_x_m)),
            "m",
        )
        .row(
            "phase_measured_deg",
            "measured phi",
            v(|m| f32v(m.phase_rad.to_degrees())),
            "deg",
        )
        .row("amp_z_peak_m", "peak duz", v(|m| f32v(m.amp_z_peak_m)), "m")
    }
}

/// The closed loop's state (`device control`): the setting, the model's
/// plan and the last update.
pub fn control(s: &ControlState) -> Report {
    let c = &s.setting;
    let u = &s.last;
    Report::default()
        .row("on", "loop on", c.on, "")
        .row("target_mu", "setpoint mu*", f32v(c.target_mu), "")
        .row("v0", "at v0", f32v(c.v0_m_s), "m/s")
        .row("gain", "gain kappa", f32v(c.gain), "")
        .row("periods", "periods per update", c.periods, "")
        .row("rate", "rate limit", f32v(c.rate_m_per_s), "m/s")
        .row(
            "duz_feedforward",
            "feedforward duz",
            f32v(s.feedforward_m),
            "m",
        )
        .row("slope_per_m", "model dmu/dduz", f32v(s.slope_per_m), "1/m")
        .row("duz_limit", "lift-off limit", f32v(s.limit_m), "m")
        .row("update", "updates", u.update, "")
        .row("measured_mu", "measured mu", f32v(u.measured_mu), "")
        .std_error(u.std_error)
        .row("duz", "commanded duz", f32v(u.amp_z_m), "m")
        .row("duz_trim", "integral trim", f32v(u.integral_m), "m")
        .row("saturated", "limited", u.saturated, "")
        .row("held", "held", u.held, "")
}

/// One closed-loop update (`device watch` while the loop runs).
pub fn control_update(u: &ControlUpdate) -> Report {
    Report::default()
        .row("update", "update", u.update, "")
        .row("target_mu", "setpoint mu*", f32v(u.target_mu), "")
        .row("measured_mu", "measured mu", f32v(u.measured_mu), "")
        .std_error(u.std_error)
        .row("duz", "commanded duz", f32v(u.amp_z_m), "m")
        .row("duz_trim", "integral trim", f32v(u.integral_m), "m")
        .row("saturated", "limited", u.saturated, "")
        .row("held", "held", u.held, "")
}

/// JSON keys and text labels of one channel's rows (normal, tangential).
const KEYS: [[(&str, &str, &str); 13]; 2] = [
    [
        ("resonance_z_hz", "normal resonance f_r", "Hz"),
        ("resonance_z_hz_lo", "  95 % interval from", "Hz"),
        ("resonance_z_hz_hi", "  95 % interval to", "Hz"),
        ("q_z", "normal Q", ""),
        ("q_z_lo", "  95 % interval from", ""),
        ("q_z_hi", "  95 % interval to", ""),
        ("gain_z_m_per_v", "normal static gain", "m/V"),
        ("gain_z_m_per_v_lo", "  95 % interval from", "m/V"),
        ("gain_z_m_per_v_hi", "  95 % interval to", "m/V"),
        ("phase_lag_z_deg", "normal extra lag", "deg"),
        ("tau_z_ms", "normal tau = Q/(pi f_r)", "ms"),
        ("fit_rms_z_pct", "normal fit residual (RMS)", "%"),
        ("points_z", "normal points", ""),
    ],
    [
        ("resonance_x_hz", "tangential resonance f_r", "Hz"),
        ("resonance_x_hz_lo", "  95 % interval from", "Hz"),
        ("resonance_x_hz_hi", "  95 % interval to", "Hz"),
        ("q_x", "tangential Q", ""),
        ("q_x_lo", "  95 % interval from", ""),
        ("q_x_hi", "  95 % interval to", ""),
        ("gain_x_m_per_v", "tangential static gain", "m/V"),
        ("gain_x_m_per_v_lo", "  95 % interval from", "m/V"),
        ("gain_x_m_per_v_hi", "  95 % interval to", "m/V"),
        ("phase_lag_x_deg", "tangential extra lag", "deg"),
        ("tau_x_ms", "tangential tau = Q/(pi f_r)", "ms"),
        ("fit_rms_x_pct", "tangential fit residual (RMS)", "%"),
        ("points_x", "tangential points", ""),
    ],
];

/// The report of an identification (`device identify`): per channel fitted
/// the mode's values with their 95 % intervals, then whether it was stored
/// and the time it took.
pub fn identification(results: &[ChannelFit], stored: bool, elapsed: f64) -> Report {
    let mut r = Report::default();
    for ch in results {
        let Ok(f) = &ch.fit else { continue };
        let keys = &KEYS[usize::from(ch.name != "normal")];
        let tau_ms = 1e3 * f.q.value / (std::f64::consts::PI * f.resonance_hz.value);
        let vals = [
            f.resonance_hz.value,
            f.resonance_hz.lo,
            f.resonance_hz.hi,
            f.q.value,
            f.q.lo,
            f.q.hi,
            f.gain_m_per_v.value,
            f.gain_m_per_v.lo,
            f.gain_m_per_v.hi,
            f.phase_lag_rad.value.to_degrees(),
            tau_ms,
            100.0 * f.rel_rms,
            f.points as f64,
        ];
        for ((k, l, u), v) in keys.iter().zip(vals) {
            r = r.row(k, l, sig(v), u);
        }
    }
    r.row("stored", "stored on the device", stored, "").row(
        "elapsed_s",
        "elapsed",
        (elapsed * 10.0).round() / 10.0,
        "s",
    )
}

/// `x` to 7 significant digits (the fit's f32 on the device holds about as many).
fn sig(x: f64) -> f64 {
    format!("{x:.6e}").parse().unwrap_or(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_aligned_with_units_and_json_is_flat() {
        let r = contact(&Contact {
            mu0: 0.3,
            kz: 1e7,
            kx: 2.5e6,
        });
        assert_eq!(r.text(), "mu0  0.3\nkz   10000000 N/m\nkx   2500000 N/m\n");
        assert_eq!(
            r.json(),
            serde_json::json!({"mu0": 0.3, "kz": 1e7, "kx": 2.5e6})
        );
    }

    #[test]
    fn self_test_line_and_keys() {
        use board::protocol::self_test::*;
        let t = |ran, failed, hse_hz, sysclk_hz| SelfTest {
            ran,
            failed,
            hse_hz,
            sysclk_hz,
        };
        assert_eq!(self_test_text(&SelfTest::NOT_RUN), "not run");
        assert_eq!(
            self_test_text(&t(ALL, 0, 8_000_000, 168_000_000)),
            "passed (HSE 8.000 MHz, SYSCLK 168.0 MHz)"
        );
        // Checks that did not run are named; an unknown bit as 0x….
        assert_eq!(
            self_test_text(&t(CLOCK_READY | 0x100, CLOCK_READY | 0x100, 0, 0)),
            "FAILED: clock_ready, 0x100 (not run: hse_frequency, sysclk, flash_latency, \
             dma_setup, streams_running)"
        );
        let r = Report::default().self_test(&t(ALL, DMA_SETUP, 7_990_000, 0));
        assert_eq!(r.text(), "self-test  FAILED: dma_setup (HSE 7.990 MHz)\n");
        assert_eq!(
            r.json(),
            serde_json::json!({
                "self_test_ran": ["clock_ready", "hse_frequency", "sysclk", "flash_latency",
                                  "dma_setup", "streams_running"],
                "self_test_failed": ["dma_setup"],
                "hse_hz": 7_990_000,
                "sysclk_hz": null,
            })
        );
    }

    #[test]
    fn status_shows_the_dsp_load_or_null() {
        let t = board::dds::SineTable::<256>::libm();
        let c = Contact {
            mu0: 0.3,
            kz: 1e7,
            kx: 1e7,
        };
        let dev = board::device::Device::new(board::device::DeviceConfig::driver_board(1), &t, c)
            .expect("the board's configuration");
        // v8: 12.5 % now, 28.75 % at most (exact in f32 and in decimal).
        let mut s = dev.status();
        (s.cpu_load_pct, s.cpu_load_max_pct) = (Some(12.5), Some(28.75));
        let r = status(&s);
        let line = |text: &str, label: &str| -> Vec<String> {
            text.lines()
                .find(|l| l.starts_with(&format!("{label}  ")))
                .map(|l| l.split_whitespace().map(str::to_string).collect())
                .unwrap_or_default()
        };
        let text = r.text();
        assert_eq!(line(&text, "cpu load"), ["cpu", "load", "12.5", "%"]);
        assert_eq!(
            line(&text, "cpu load max"),
            ["cpu", "load", "max", "28.75", "%"]
        );
        let j = r.json();
        assert_eq!(
            (&j["cpu_load_pct"], &j["cpu_load_max_pct"]),
            (&serde_json::json!(12.5), &serde_json::json!(28.75))
        );
        // A device that does not measure itself (the virtual device): `-` and null.
        let r = status(&dev.status());
        assert_eq!(line(&r.text(), "cpu load"), ["cpu", "load", "-", "%"]);
        let j = r.json();
        assert!(
            j["cpu_load_pct"].is_null() && j["cpu_load_max_pct"].is_null(),
            "{j}"
        );
    }
}
