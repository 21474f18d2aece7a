//! The DDS of the driver board: packing, frequency and phase exactness, no
//! drift, ramps and slew limits, clamping, refusals that leave the state
//! untouched, and nearest-entry reads. The spectral purity of the 12-bit
//! output (SFDR, worst error in LSB) over table sizes, interpolation and
//! backends is measured by `fricctl bench dac` and checked against the
//! closed forms in `host-cli/tests/cli.rs`.

use std::f64::consts::{PI, TAU};

use board::dds::{
    pack_dual, phase_rad, phase_word, quantise, unpack_dual, Dds, DdsError, Interp, Level,
    SineTable, Slew,
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
