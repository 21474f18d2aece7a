//! The DDS of the driver board: packing, frequency and phase exactness, no
//! drift, ramps and slew limits, clamping, refusals that leave the state
//! untouched, and nearest-entry reads. The spectral purity of the 12-bit
//! output (SFDR, worst error in LSB) over table sizes, interpolation and
//! backends is measured by `fricctl bench dac` and checked against the
//! closed forms in `host-cli/tests/cli.rs`.

use std::f64::consts::{PI, SQRT_2, TAU};

use board::dds::{
    pack_dual, phase_rad, phase_word, quantise, unpack_dual, Dds, DdsError, FillPath, Interp,
    Level, SineTable, Slew,
};

const FS: f64 = 1_000_000.0;

fn fast_slew() -> Slew {
    Slew {
        amp_per_sample: 1e9,
        dc_per_sample: 1e9,
        phase_per_sample: u32::MAX / 2,
    }
}

#[test]
fn packing_matches_dhr12rd_layout() {
    assert_eq!(pack_dual(0xABC, 0x123), 0x0123_0ABC);
    assert_eq!(pack_dual(4095, 0), 0x0000_0FFF);
    assert_eq!(pack_dual(0, 4095), 0x0FFF_0000);
    // Bits 12–15 and 28–31 are reserved: never set.
    assert_eq!(pack_dual(0xFFFF, 0xFFFF) & 0xF000_F000, 0);
    for (a, b) in [(0, 0), (1, 4094), (2048, 17)] {
        assert_eq!(unpack_dual(pack_dual(a, b)), (a, b));
    }
}

#[test]
fn quantise_rounds_and_clamps() {
    assert_eq!(quantise(-5.0), 0);
    assert_eq!(quantise(f32::NAN), 0);
    assert_eq!(quantise(5000.0), 4095);
    assert_eq!(quantise(4094.6), 4095);
    assert_eq!(quantise(2047.49), 2047);
    assert_eq!(quantise(2047.5), 2048);
}

#[test]
fn frequency_is_exact_and_sub_hz() {
    let t = SineTable::<1024>::libm();
    let mut d = Dds::new(&t, FS, fast_slew()).unwrap();
    for f in [20_000.0, 39_999.7, 40_000.0, 40_000.3, 123_456.789] {
        let a = d.set_frequency(f).unwrap();
        assert_eq!(a.freq_hz, a.tuning_word as f64 * FS / 4_294_967_296.0);
        // Resolution f_s/2³² = 0.23 mHz: the error is at most half of it.
        assert!(
            (a.freq_hz - f).abs() <= FS / 2f64.powi(33) + 1e-9,
            "{f}: {}",
            a.freq_hz
        );
    }
    // Refusals leave the running frequency alone.
    let before = d.tuning_word();
    for bad in [0.0, -1.0, f64::NAN, FS / 2.0, 1e-6] {
        assert_eq!(d.set_frequency(bad), Err(DdsError::Frequency), "{bad}");
        assert_eq!(d.tuning_word(), before);
    }
}

/// Phase of the fundamental of a code sequence at the drive frequency (DFT bin).
fn fundamental(codes: &[f64], phases: &[u32]) -> (f64, f64) {
    let (mut re, mut im) = (0.0, 0.0);
    let mean = codes.iter().sum::<f64>() / codes.len() as f64;
    for (c, &p) in codes.iter().zip(phases) {
        let th = phase_rad(p);
        re += (c - mean) * th.cos();
        im += (c - mean) * th.sin();
    }
    // c ≈ A sin(θ + ψ) ⇒ Σ c cos θ = (n/2) A sin ψ, Σ c sin θ = (n/2) A cos ψ.
    let n = codes.len() as f64;
    (2.0 * (re * re + im * im).sqrt() / n, re.atan2(im))
}

#[test]
fn phase_between_channels_is_exact_and_does_not_drift() {
    let t = SineTable::<1024>::libm();
    let mut d = Dds::new(&t, FS, fast_slew()).unwrap();
    // 40 kHz · 997/1000: not a divisor of f_s, so every table position is used.
    d.set_frequency(39_880.0).unwrap();
    let lvl = Level {
        amp: 2000.0,
        dc: 2048.0,
    };
    d.set_level(0, lvl).unwrap();
    d.set_level(1, lvl).unwrap();
    let phi = 1.234_567;
    d.set_phase(0, 0);
    let exact = d.set_phase(1, phase_word(phi));
    assert!((exact - phi).abs() <= TAU / 2f64.powi(33));
    let measure = |d: &mut Dds<'_, 1024>| {
        let (mut c1, mut c2, mut ph) = (Vec::new(), Vec::new(), Vec::new());
        // Whole periods only (997 periods in 25 000 samples).
        for _ in 0..25_000 {
            let (p, a, b) = d.next_codes();
            c1.push(f64::from(a));
            c2.push(f64::from(b));
            ph.push(p);
        }
        let (_, p1) = fundamental(&c1, &ph);
        let (_, p2) = fundamental(&c2, &ph);
        (p2 - p1).rem_euclid(TAU)
    };
    let first = measure(&mut d);
    // The integer offsets are exact by construction.
    assert!((d.phase_between() - exact).abs() < 1e-15);
    // Skip ahead 10⁸ samples (100 s of output) and measure again.
    for _ in 0..100_000_000u32 / 1000 {
        for _ in 0..1000 {
            d.next_codes();
        }
    }
    let last = measure(&mut d);
    // Measured phase equals the command to within the 12-bit quantisation and
    // table interpolation (≪ 1 mrad), identically early and late.
    assert!((first - phi).abs() < 2e-4, "{first} vs {phi}");
    assert!((last - phi).abs() < 2e-4, "{last} vs {phi}");
    // The offsets themselves have not moved by a single phase-word unit.
    assert!((d.phase_between() - exact).abs() < 1e-15);
}

#[test]
fn ramps_respect_the_slew_limit_and_soft_stop() {
    let t = SineTable::<256>::libm();
    let slew = Slew::from_rates(FS as f32, 1e6, 1e6, 1e3).unwrap(); // 1 code/sample, 1 mrad/sample
    let mut d = Dds::new(&t, FS, slew).unwrap();
    d.set_frequency(40_000.0).unwrap();
    d.set_level(
        0,
        Level {
            amp: 1000.0,
            dc: 2048.0,
        },
    )
    .unwrap();
    let mut prev = d.channels()[0];
    let mut n = 0;
    while !d.settled() {
        d.next_codes();
        let c = d.channels()[0];
        assert!((c.amp - prev.amp).abs() <= 1.0 + 1e-3 && (c.dc - prev.dc).abs() <= 1.0 + 1e-3);
        prev = c;
        n += 1;
        assert!(n < 10_000);
    }
    // DC 0 → 2048 at 1 code/sample takes 2048 samples.
    assert!((2040..=2060).contains(&n), "{n}");
    // A phase step of π/2 on channel 2 is spread over π/2 / (1e-3 rad per sample) ≈ 1571 samples.
    d.set_level(
        1,
        Level {
            amp: 1000.0,
            dc: 2048.0,
        },
    )
    .unwrap();
    while !d.settled() {
        d.next_codes();
    }
    d.set_phase(1, phase_word(PI / 2.0));
    let mut max_jump = 0i32;
    let mut last = d.next_codes().2 as i32;
    let mut steps = 0;
    while !d.settled() {
        let b = d.next_codes().2 as i32;
        max_jump = max_jump.max((b - last).abs());
        last = b;
        steps += 1;
    }
    assert!((1565..=1575).contains(&steps), "{steps}");
    // Without the phase ramp the largest step of a 1000-code, 40 kHz sine at 1 MS/s
    // is 2π·1000·0.04 ≈ 252 codes; the ramp adds at most 1000·1e-3 = 1 code.
    assert!(max_jump <= 254, "{max_jump}");
    // Soft stop: amplitudes ramp to 0, DC stays.
    d.ramp_down();
    let mut k = 0;
    while !d.settled() {
        d.next_codes();
        k += 1;
    }
    assert!((990..=1010).contains(&k), "{k}");
    assert_eq!(d.channels()[0].amp, 0.0);
    assert_eq!(d.channels()[0].dc, 2048.0);
}

#[test]
fn out_of_range_levels_are_refused_and_change_nothing() {
    let t = SineTable::<256>::libm();
    let mut d = Dds::new(&t, FS, fast_slew()).unwrap();
    d.set_level(
        0,
        Level {
            amp: 100.0,
            dc: 2000.0,
        },
    )
    .unwrap();
    let before = *d.channels();
    for bad in [
        Level {
            amp: 3000.0,
            dc: 2048.0,
        },
        Level {
            amp: 100.0,
            dc: 50.0,
        },
        Level {
            amp: -100.0,
            dc: 4050.0,
        },
        Level {
            amp: f32::NAN,
            dc: 2048.0,
        },
        Level {
            amp: 1.0,
            dc: f32::INFINITY,
        },
    ] {
        assert_eq!(d.set_level(0, bad), Err(DdsError::Level), "{bad:?}");
        assert_eq!(*d.channels(), before);
    }
    assert_eq!(Slew::from_rates(1e6, 0.0, 1.0, 1.0), Err(DdsError::Slew));
    // A sample rate of zero (or below, or not finite) would give infinite
    // steps per sample.
    for fs in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert_eq!(
            Slew::from_rates(fs, 1.0, 1.0, 1.0),
            Err(DdsError::SampleRate),
            "{fs}"
        );
    }
    assert!(Dds::new(&t, f64::NAN, fast_slew()).is_err());
}

/// Nearest-entry reads return the table entry whose phase is closest
/// (ties round up), wrapping at the end of the table.
#[test]
fn nearest_entry_lookup() {
    let t = SineTable::<16>::libm();
    let step = 1u32 << 28; // 2³²/16
    for i in 0..16u32 {
        let at = i.wrapping_mul(step);
        assert_eq!(t.sin_nearest(at), t.entry(i as usize));
        assert_eq!(
            t.sin_nearest(at.wrapping_add(step / 2 - 1)),
            t.entry(i as usize)
        );
        assert_eq!(
            t.sin_nearest(at.wrapping_add(step / 2)),
            t.entry(i as usize + 1)
        );
        // Linear interpolation agrees at the entries.
        assert_eq!(t.sin(at), t.entry(i as usize));
    }
    // The last half step wraps to entry 0.
    assert_eq!(t.sin_nearest(u32::MAX), t.entry(0));
    // The DDS uses the chosen interpolation.
    let mut d = Dds::new(&t, FS, fast_slew()).unwrap();
    d.set_interp(Interp::Nearest);
    d.set_frequency(FS / 7.0).unwrap();
    d.set_level(
        0,
        Level {
            amp: 1000.0,
            dc: 2048.0,
        },
    )
    .unwrap();
    d.next_codes();
    for _ in 0..100 {
        let (p, a, _) = d.next_codes();
        assert_eq!(a, quantise(2048.0 + 1000.0 * t.sin_nearest(p)));
    }
}

/// A small deterministic generator (64-bit LCG, Knuth's constants): uniform
/// in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The largest error of a table's entries against f64 `sin` (ε_t of eq. Q5).
fn table_error<const N: usize>(t: &SineTable<N>) -> f64 {
    (0..N)
        .map(|i| (f64::from(t.entry(i)) - (TAU * i as f64 / N as f64).sin()).abs())
        .fold(0.0, f64::max)
}

/// Eq. R2 (board::reference): the largest error of a reference word's
/// cosine or sine on table `t` — the products (R3) of the run's first phase
/// and its step, each read within `ε_s = ε_t + (2π/N)²/8 + 2⁻²⁹`, so
/// `2√2·ε_s + 2ε_s²`; the high words' floors, 2⁻²⁷; the Q15 rounding, 2⁻¹⁶;
/// and at least the clamp of +2¹⁵, 2⁻¹⁵. The same for every step.
fn eps_r<const N: usize>(t: &SineTable<N>) -> f64 {
    let eps_s = table_error(t) + (TAU / N as f64).powi(2) / 8.0 + 2f64.powi(-29);
    (2.0 * SQRT_2 * eps_s + 2.0 * eps_s * eps_s + 2f64.powi(-27) + 2f64.powi(-16))
        .max(2f64.powi(-15))
}

/// Eq. Q7 (board::dds, the fills formed from the reference): `1/2 +
/// √2·|amp|·(ε_r + ε_φ + 3·2⁻²⁴) + √2/16 + 2⁻¹⁹`, `ε_φ` the table's
/// interpolated read (Q1).
fn q7<const N: usize>(t: &SineTable<N>, amp: f64) -> f64 {
    let eps_phi = table_error(t) + (TAU / N as f64).powi(2) / 8.0 + 2f64.powi(-29);
    0.5 + SQRT_2 * amp.abs() * (eps_r(t) + eps_phi + 3.0 * 2f64.powi(-24))
        + SQRT_2 / 16.0
        + 2f64.powi(-19)
}

/// A settled fill against its bound: with [`Interp::Reference`] (the
/// board's, `FillPath::Reference`, eq. Q6) eq. Q7, [`q7`]; reading the table
/// (`FillPath::Table`, eqs. Q1–Q3) eq. Q5, `1/2 + |amp|·(ε_t + e_read +
/// 2⁻²⁹) + 2⁻¹⁵` with `e_read` = `(2π/N)²/8` (linear) or `π/N` (nearest).
/// The exact value is formed here in f64 from the phase words alone
/// (accumulator, tuning word, offsets), never through the DDS's table or
/// reference. A code that differs from `round(exact)` must sit within the
/// bound's excess over 1/2 of a tie. Returns the worst error and the worst
/// ratio of error to bound.
fn check_fill_against_f64<const N: usize>(
    t: &SineTable<N>,
    interp: Interp,
    cases: u32,
) -> (f64, f64) {
    let eps_t = table_error(t);
    let step = TAU / N as f64;
    let read_err = match interp {
        Interp::Nearest => step / 2.0,
        _ => step * step / 8.0,
    };
    let mut rng = Lcg(0x0123_4567_89ab_cdef);
    let (mut worst, mut ratio): (f64, f64) = (0.0, 0.0);
    for _ in 0..cases {
        let mut d = Dds::new(t, FS, fast_slew()).unwrap();
        d.set_interp(interp);
        d.set_frequency(1e3 + 2e5 * rng.next()).unwrap();
        let mut lv = [(0.0f32, 0.0f32); 2];
        for (ch, l) in lv.iter_mut().enumerate() {
            let amp = (4094.0 * rng.next() - 2047.0) as f32;
            let room = 4095.0 - 2.0 * f64::from(amp.abs());
            let dc = (f64::from(amp.abs()) + room * rng.next()) as f32;
            *l = (amp, dc);
            d.set_level(ch, Level { amp, dc }).unwrap();
            d.set_phase(ch, (rng.next() * 4_294_967_296.0) as u32);
        }
        // One sample applies the targets (fast slew): settled from here.
        d.next_codes();
        assert!(d.settled());
        let path = d.fill_path();
        assert_eq!(
            path == FillPath::Reference,
            interp == Interp::Reference,
            "{interp:?}"
        );
        let (acc0, tw) = (d.accumulator(), d.tuning_word());
        let ph = [d.channels()[0].phase, d.channels()[1].phase];
        let mut buf = [0u32; 64];
        d.fill(&mut buf);
        for (i, &w) in buf.iter().enumerate() {
            let p = acc0.wrapping_add(tw.wrapping_mul(i as u32));
            let codes = unpack_dual(w);
            for (ch, code) in [codes.0, codes.1].into_iter().enumerate() {
                let (amp, dc) = (f64::from(lv[ch].0), f64::from(lv[ch].1));
                let theta = phase_rad(p.wrapping_add(ph[ch]));
                let exact = dc + amp * theta.sin();
                let bound = match path {
                    FillPath::Reference => q7(t, amp),
                    FillPath::Table => {
                        0.5 + amp.abs() * (eps_t + read_err + 2f64.powi(-29)) + 2f64.powi(-15)
                    }
                };
                let err = (f64::from(code) - exact).abs();
                assert!(
                    err <= bound,
                    "{interp:?} ch {ch} sample {i}: {code} vs {exact} (bound {bound})"
                );
                if f64::from(code) != exact.round() {
                    let tie = (exact - exact.floor() - 0.5).abs();
                    assert!(tie <= bound - 0.5, "{code} vs {exact}: not a near tie");
                }
                worst = worst.max(err);
                ratio = ratio.max(err / bound);
            }
        }
    }
    (worst, ratio)
}

#[test]
fn integer_fill_is_within_the_derived_bound_of_the_exact_sine() {
    let t = SineTable::<1024>::libm();
    // The entries are libm's f32 sine of an f32 argument 2πk/N, |k| ≤ N/2:
    // the argument rounds by ≤ |x|·2⁻²³ (the constant 2π and the product),
    // the sine by one ulp (2⁻²⁴ below 1): ε_t ≤ π·2⁻²³ + 2⁻²⁴ = 4.3e-7.
    let eps_t = table_error(&t);
    assert!(eps_t <= PI * 2f64.powi(-23) + 2f64.powi(-24), "{eps_t}");
    let (worst, _) = check_fill_against_f64(&t, Interp::Linear, 300);
    // Eq. Q5 at |amp| ≤ 2047 (ε_t = 2.0e-7 measured): ≈ 0.5101 LSB.
    let at_full =
        0.5 + 2047.0 * (eps_t + (TAU / 1024.0).powi(2) / 8.0 + 2f64.powi(-29)) + 2f64.powi(-15);
    assert!(worst <= at_full && at_full < 0.5102, "{worst} {at_full}");
    check_fill_against_f64(&t, Interp::Nearest, 50);
    // The board's: eq. Q7 at |amp| ≤ 2047, any step (ε_r ≤ 3.06e-5,
    // `tests/tests/reference.rs`): ≤ 0.70 LSB.
    let (worst, _) = check_fill_against_f64(&t, Interp::Reference, 300);
    let at_full = q7(&t, 2047.0);
    assert!(worst <= at_full && at_full < 0.70, "{worst} {at_full}");
    // A coarse table, where its reads dominate: 2047·(2π/64)²/8 = 2.47 LSB
    // (Q5); Q7 ≈ 7.7 LSB (ε_r and ε_φ near 1.2e-3 each). Each bound is
    // reached within a factor of three.
    let t64 = SineTable::<64>::libm();
    let (worst, ratio) = check_fill_against_f64(&t64, Interp::Linear, 100);
    assert!(worst > 1.5 && ratio > 1.0 / 3.0, "{worst} {ratio}");
    let (worst, ratio) = check_fill_against_f64(&t64, Interp::Reference, 100);
    assert!(
        ratio > 1.0 / 3.0,
        "{worst} {ratio}: the bound is loose by a factor"
    );
}

/// Eq. Q4: while ramping, sample `i` of a fill uses amplitude, DC and phase
/// offset `i` slew steps on; checked in f64 against the closed form
/// `x_0 + clamp(x_target − x_0, ±i·s)`, with eq. Q5's bound widened by the
/// slews' rounding to the units of (Q2): `i·2⁻¹⁸` of amplitude and `i·2⁻¹⁶`
/// of DC per sample (|sin| ≤ 1).
#[test]
fn integer_ramps_follow_the_slew_closed_form() {
    ramp_case(
        [(1800.0, 2047.0), (-1000.0, 1500.0)],
        [40_000_000, 4_200_000_000],
        6,
    );
}

/// [`integer_ramps_follow_the_slew_closed_form`] with one quantity ramping
/// at a time while the others stay (the board's voltage mode ramps the
/// amplitude alone): each takes the general ramp, never the one-step
/// fill, whose condition must hold for all three. The amplitude also
/// through zero (+300 → −300 codes: the one-step test's distance, not the
/// sum of the two factors, decides).
#[test]
fn one_quantity_ramping_alone_follows_the_slew_closed_form() {
    // (amplitude, DC) targets of both channels from (300, 2000), phase
    // targets from 0; fills until settled.
    ramp_case([(1800.0, 2000.0), (1000.0, 2000.0)], [0, 0], 6);
    ramp_case([(-300.0, 2000.0), (-300.0, 2000.0)], [0, 0], 2);
    ramp_case([(300.0, 2047.0), (300.0, 1950.0)], [0, 0], 2);
    ramp_case(
        [(300.0, 2000.0), (300.0, 2000.0)],
        [40_000_000, 4_200_000_000],
        2,
    );
}

/// From both channels settled at amplitude 300, DC 2000 codes, phase 0
/// (39 880 Hz), slews 7.3 codes, 1.9 codes and 3e6 words per sample toward
/// `targets` and `ph_target`: `fills` fills of 64, each code against the
/// closed form of eq. Q4 in f64, the state after each fill likewise, and
/// settled at the end.
fn ramp_case(targets: [(f32, f32); 2], ph_target: [u32; 2], fills: usize) {
    let t = SineTable::<1024>::libm();
    let eps = table_error(&t) + (TAU / 1024.0).powi(2) / 8.0 + 2f64.powi(-29);
    let mut d = Dds::new(&t, FS, fast_slew()).unwrap();
    d.set_frequency(39_880.0).unwrap();
    let (a0, dc0) = (300.0f32, 2000.0f32);
    for ch in 0..2 {
        d.set_level(ch, Level { amp: a0, dc: dc0 }).unwrap();
    }
    d.next_codes();
    assert!(d.settled());
    let slew = Slew {
        amp_per_sample: 7.3,
        dc_per_sample: 1.9,
        phase_per_sample: 3_000_000,
    };
    d.set_slew(slew);
    for ch in 0..2 {
        let (amp, dc) = targets[ch];
        d.set_level(ch, Level { amp, dc }).unwrap();
        d.set_phase(ch, ph_target[ch]);
    }
    let mut total = 0usize;
    // Fills until settled: the amplitude's 1500 codes at 7.3 per sample take
    // 206 samples, four fills.
    for _ in 0..fills {
        let before = *d.channels();
        let (acc0, tw) = (d.accumulator(), d.tuning_word());
        // A ramp reads the table (Q5 plus the slews' rounding); a fill whose
        // levels all arrive within a sample, or a settled one, is formed from
        // the reference (Q7): the ramp's last fill may be either.
        let path = d.fill_path();
        let mut buf = [0u32; 64];
        d.fill(&mut buf);
        for (i, &w) in buf.iter().enumerate() {
            let n = i as f64;
            let p = acc0.wrapping_add(tw.wrapping_mul(i as u32));
            let codes = unpack_dual(w);
            for (ch, code) in [codes.0, codes.1].into_iter().enumerate() {
                let c = before[ch];
                let toward = |x: f32, to: f32, s: f32| {
                    let (x, to, s) = (f64::from(x), f64::from(to), f64::from(s));
                    x + (to - x).clamp(-s * n, s * n)
                };
                let amp = toward(c.amp, c.amp_target, slew.amp_per_sample);
                let dc = toward(c.dc, c.dc_target, slew.dc_per_sample);
                let dph = f64::from(c.phase_target.wrapping_sub(c.phase) as i32);
                let lim = f64::from(slew.phase_per_sample) * n;
                let ph = c
                    .phase
                    .wrapping_add(dph.clamp(-lim, lim) as i64 as i32 as u32);
                let exact = (dc + amp * phase_rad(p.wrapping_add(ph)).sin()).clamp(0.0, 4095.0);
                let bound = match path {
                    FillPath::Table => {
                        0.5 + amp.abs() * eps
                            + 2f64.powi(-15)
                            + n * (2f64.powi(-18) + 2f64.powi(-16))
                    }
                    FillPath::Reference => q7(&t, amp),
                };
                let err = (f64::from(code) - exact).abs();
                assert!(
                    err <= bound,
                    "ch {ch} sample {i}: {code} vs {exact} ({bound})"
                );
            }
        }
        total += 64;
        // The state moved on by 64 steps, in the same closed form.
        for (c, b) in d.channels().iter().zip(&before) {
            let want = f64::from(b.amp)
                + f64::from(b.amp_target - b.amp).clamp(
                    -64.0 * f64::from(slew.amp_per_sample),
                    64.0 * f64::from(slew.amp_per_sample),
                );
            assert!(
                (f64::from(c.amp) - want).abs() <= 1e-3,
                "{} vs {want}",
                c.amp
            );
        }
    }
    assert!(d.settled(), "after {total} samples");
}

/// Eq. Q4 with a slew of one whole step (the displacement loops' fills,
/// `Dds::fill`'s one-step path): a change of every level and phase made
/// between fills gives sample 0 at the levels before and samples 1… at the
/// new ones — each code within (Q5) of the exact `dc + amp·sin` formed in
/// f64 from the phase words alone — and the DDS settled after the fill.
/// A DC change beyond one sample's slew takes the general ramp (checked
/// by `integer_ramps_follow_the_slew_closed_form`); here it stays within.
#[test]
fn a_one_step_change_fills_the_old_levels_once_then_the_new() {
    let t = SineTable::<1024>::libm();
    let eps_t = table_error(&t);
    let read_err = (TAU / 1024.0).powi(2) / 8.0;
    let mut rng = Lcg(0x5eed_0f0e_5eed_0f0e);
    for case in 0..200 {
        // The board's fills from the reference (Q7), and from the table
        // (Q5), in turn.
        let interp = if case % 2 == 0 {
            Interp::Reference
        } else {
            Interp::Linear
        };
        let mut d = Dds::new(&t, FS, fast_slew()).unwrap();
        d.set_interp(interp);
        d.set_frequency(1e3 + 2e5 * rng.next()).unwrap();
        let levels = |d: &mut Dds<'_, 1024>, rng: &mut Lcg| {
            let mut out = [(0.0f32, 0.0f32, 0u32); 2];
            for (ch, l) in out.iter_mut().enumerate() {
                let amp = (4094.0 * rng.next() - 2047.0) as f32;
                let room = 4095.0 - 2.0 * f64::from(amp.abs());
                let dc = (f64::from(amp.abs()) + room * rng.next()) as f32;
                let ph = (rng.next() * 4_294_967_296.0) as u32;
                d.set_level(ch, Level { amp, dc }).unwrap();
                d.set_phase(ch, ph);
                *l = (amp, dc, ph);
            }
            out
        };
        let before = levels(&mut d, &mut rng);
        d.next_codes();
        assert!(d.settled());
        // New targets, the DC kept within one sample's DC slew.
        let mut after = levels(&mut d, &mut rng);
        for (ch, a) in after.iter_mut().enumerate() {
            let dc = before[ch].1 + (a.1 - before[ch].1).clamp(-0.5, 0.5);
            let dc = dc.clamp(a.0.abs(), 4095.0 - a.0.abs());
            d.set_level(ch, Level { amp: a.0, dc }).unwrap();
            a.1 = dc;
        }
        let (acc0, tw) = (d.accumulator(), d.tuning_word());
        let path = d.fill_path();
        assert_eq!(
            path == FillPath::Reference,
            interp == Interp::Reference,
            "case {case}"
        );
        let mut buf = [0u32; 64];
        d.fill(&mut buf);
        assert!(d.settled(), "case {case}: not settled after the fill");
        for (i, &w) in buf.iter().enumerate() {
            let p = acc0.wrapping_add(tw.wrapping_mul(i as u32));
            let codes = unpack_dual(w);
            let lv = if i == 0 { before } else { after };
            for (ch, code) in [codes.0, codes.1].into_iter().enumerate() {
                let (amp, dc, ph) = (f64::from(lv[ch].0), f64::from(lv[ch].1), lv[ch].2);
                let exact = dc + amp * phase_rad(p.wrapping_add(ph)).sin();
                let bound = match path {
                    FillPath::Reference => q7(&t, amp),
                    FillPath::Table => {
                        0.5 + amp.abs() * (eps_t + read_err + 2f64.powi(-29)) + 2f64.powi(-15)
                    }
                };
                let err = (f64::from(code) - exact).abs();
                assert!(
                    err <= bound,
                    "case {case} ch {ch} sample {i}: {code} vs {exact} (bound {bound})"
                );
            }
        }
    }
}

/// `Dds::fill_with_reference` writes the reference words (eq. R1) of the
/// fill's own phases `acc0 + i·tw`: sample `i`'s to `head[i]`, then the
/// rest to `tail` (the device lays them out as the ADC sees them, `L`
/// samples late). Each word's cosine and sine within ε_r (eq. R2) of
/// the exact ones formed in f64 from the phase words alone, over settled
/// fills, fills changed within one sample and ramps, every split of the 64
/// samples from 0 to 64, and a retune between fills (the next fill starts
/// where the last ended). A `head` and `tail` too short for `buf` leave
/// both untouched and fill `buf` all the same.
#[test]
fn a_fill_writes_the_reference_words_of_its_own_phases() {
    let t = SineTable::<1024>::libm();
    let mut rng = Lcg(0x0dd5_eed5_0dd5_eed5);
    let mut d = Dds::new(&t, FS, fast_slew()).unwrap();
    d.set_frequency(20_000.0).unwrap();
    for fill in 0..130usize {
        match fill % 5 {
            // A ramp (slow slew), a change within one sample, a retune.
            0 => d.set_slew(Slew {
                amp_per_sample: 0.7,
                dc_per_sample: 0.7,
                phase_per_sample: 100_000,
            }),
            1 => d.set_slew(fast_slew()),
            2 => {
                d.set_frequency(1e3 + 9e4 * rng.next()).unwrap();
            }
            _ => {}
        }
        if fill % 5 < 2 {
            for ch in 0..2 {
                let amp = (1000.0 * rng.next()) as f32;
                d.set_level(ch, Level { amp, dc: 2047.0 }).unwrap();
                d.set_phase(ch, (rng.next() * 4_294_967_296.0) as u32);
            }
        }
        let (acc0, tw) = (d.accumulator(), d.tuning_word());
        // The empty head and the empty tail, then splits across the block,
        // each on every kind of fill (five fills in a row share one).
        let split = match fill / 5 {
            0 => 0,
            1 => 64,
            k => (k * 11) % 65,
        };
        let (mut head, mut tail) = ([0u32; 64], [0u32; 64]);
        let mut buf = [0u32; 64];
        let (path, before) = (d.fill_path(), *d.channels());
        assert!(d.fill_with_reference(&mut buf, &mut head[..split], &mut tail[..64 - split]));
        assert_eq!(d.accumulator(), acc0.wrapping_add(tw.wrapping_mul(64)));
        // A fill from the words: sample 0 at the levels now, the rest at the
        // targets', each code within Q7 of the exact value in f64.
        if path == FillPath::Reference {
            for (i, &w) in buf.iter().enumerate() {
                let p = acc0.wrapping_add(tw.wrapping_mul(i as u32));
                let codes = unpack_dual(w);
                for (ch, code) in [codes.0, codes.1].into_iter().enumerate() {
                    let c = before[ch];
                    let (amp, dc, ph) = if i == 0 {
                        (c.amp, c.dc, c.phase)
                    } else {
                        (c.amp_target, c.dc_target, c.phase_target)
                    };
                    let (amp, dc) = (f64::from(amp), f64::from(dc));
                    let exact = dc + amp * phase_rad(p.wrapping_add(ph)).sin();
                    let bound = q7(&t, amp);
                    assert!(
                        (f64::from(code) - exact).abs() <= bound,
                        "fill {fill} split {split} ch {ch} sample {i}: {code} vs {exact}"
                    );
                }
            }
        }
        let bound = eps_r(&t);
        for i in 0..64 {
            let w = if i < split { head[i] } else { tail[i - split] };
            let th = phase_rad(acc0.wrapping_add(tw.wrapping_mul(i as u32)));
            let (c, s) = (
                f64::from(board::reference::cos_of(w)) / 32_768.0,
                f64::from(board::reference::sin_of(w)) / 32_768.0,
            );
            assert!(
                (c - th.cos()).abs() <= bound && (s - th.sin()).abs() <= bound,
                "fill {fill} sample {i}: ({c}, {s}) vs θ {th} (bound {bound})"
            );
        }
    }
    // Too few words: `buf` is filled, nothing written to them.
    let (mut head, mut tail) = ([7u32; 10], [7u32; 10]);
    let mut buf = [0u32; 64];
    let mut other = d.clone();
    assert!(!d.fill_with_reference(&mut buf, &mut head, &mut tail));
    assert_eq!((head, tail), ([7u32; 10], [7u32; 10]));
    let mut want = [0u32; 64];
    other.fill(&mut want);
    assert_eq!(buf, want);
}

/// `SineTable::sin` (linear interpolation between entries) against f64
/// `sin` at 10 000 phase words: within the table's own error `ε_t`, the
/// interpolation's `(π/N)²/2` (the chord of a sine over `2π/N`: `max |sin''|
/// h²/8`, `h = 2π/N`) and f32's rounding of the fraction and the
/// product-sum (`3·2⁻²⁴`). With the fraction's scale wrong (a remainder for
/// the `1/2²⁴`) the error is the full slope times a fraction up to 2⁸.
#[test]
fn the_interpolated_sine_is_within_its_bound() {
    let t = SineTable::<1024>::libm();
    let bound = table_error(&t) + (PI / 1024.0).powi(2) / 2.0 + 3.0 * 2f64.powi(-24);
    let mut rng = Lcg(7);
    let mut worst = 0.0f64;
    for _ in 0..10_000 {
        let p = (rng.next() * 4_294_967_296.0) as u32;
        let exact = (TAU * f64::from(p) / 4_294_967_296.0).sin();
        worst = worst.max((f64::from(t.sin(p)) - exact).abs());
    }
    assert!(worst <= bound, "{worst:e} > {bound:e}");
    // Not only at the entries: the interpolation is exercised.
    assert!(worst > table_error(&t), "{worst:e}");
}
