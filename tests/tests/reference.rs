//! The ADC block's shared reference (`board::reference`, issue 35): its Q15
//! cosine and sine against f64 (eq. R2), the integer pair sums against
//! straightforward i64 sums, the rail check against the rule it encodes
//! (every count of the 12-bit converter), and the force estimator fed in
//! blocks against the closed form of a synthetic force.

use std::f64::consts::{SQRT_2, TAU};

use board::dds::{phase_rad, SineTable};
use board::estimator::{Calibration, Estimator};
use board::reference::{
    any_railed, cos_of, sin_of, Gram, PairSums, Reference, ADC_FULL_SCALE, BLOCK,
};
use integration_tests::Rng;

/// The table's own error against f64: `max |t_i − sin(2πi/N)|`.
fn table_error<const N: usize>(t: &SineTable<N>) -> f64 {
    (0..N)
        .map(|i| (f64::from(t.entry(i)) - (TAU * i as f64 / N as f64).sin()).abs())
        .fold(0.0, f64::max)
}

/// Eq. R2: every word of a block's reference is within `ε_r = 2√2·ε_s +
/// 2ε_s² + 2⁻²⁷ + 2⁻¹⁶` (`ε_s = ε_t + (2π/N)²/8 + 2⁻²⁹`, each Q30 read of
/// the run's first phase and of its steps; the high words' floors; the Q15
/// rounding) of cos θ_i, sin θ_i, θ_i formed in f64 from the phase words
/// alone, and within `max(ε_r, 2⁻¹⁵)` where the value is within `ε_r` of
/// +1 (the saturation of `+2¹⁵`; elsewhere a rounding that is a floor, or
/// off by one unit, fails): 3 000 blocks of 64 at random start words and
/// steps (every step size up to half a turn and beyond, which turns
/// backwards), and blocks starting just before 0 and a quarter turn, where
/// the saturation acts. The bound is ≤ 3.06e-5 for any step; it is reached
/// within a factor of two.
#[test]
fn the_q15_reference_is_within_its_derived_bound() {
    let t = SineTable::<1024>::libm();
    let eps_t = table_error(&t);
    let eps_s = eps_t + (TAU / 1024.0).powi(2) / 8.0 + 2f64.powi(-29);
    let inner = 2.0 * SQRT_2 * eps_s + 2.0 * eps_s * eps_s + 2f64.powi(-27) + 2f64.powi(-16);
    assert!(inner.max(2f64.powi(-15)) <= 3.06e-5, "{inner}");
    let board_max = (100e3 / 500e3 * 4_294_967_296.0) as u32;
    let mut rng = Rng::new(7);
    let (mut worst, mut worst_saturated) = (0.0f64, 0.0f64);
    for k in 0..3_000u32 {
        let tw = match k % 4 {
            0 => (rng.uniform() * 4_294_967_296.0) as u32,
            1 => (rng.uniform() * 1e9) as u32,
            2 => (rng.uniform() * 1e6) as u32 + 1,
            _ => board_max - (rng.uniform() * 1e8) as u32,
        };
        let acc0 = match k % 3 {
            0 => 0u32.wrapping_sub((rng.uniform() * 1e7) as u32),
            1 => (1u32 << 30).wrapping_sub((rng.uniform() * 1e7) as u32),
            _ => (rng.uniform() * 4_294_967_296.0) as u32,
        };
        // The saturation's share only near +1 (R1: only +2¹⁵ is clamped).
        let bound = |x: f64| {
            if x >= 1.0 - inner {
                inner.max(2f64.powi(-15))
            } else {
                inner
            }
        };
        let r = Reference::new(&t, acc0, tw, BLOCK);
        for (i, &w) in r.words().iter().enumerate() {
            let th = phase_rad(acc0.wrapping_add(tw.wrapping_mul(i as u32)));
            let ec = (f64::from(cos_of(w)) / 32_768.0 - th.cos()).abs();
            let es = (f64::from(sin_of(w)) / 32_768.0 - th.sin()).abs();
            let (bc, bs) = (bound(th.cos()), bound(th.sin()));
            assert!(
                ec <= bc && es <= bs,
                "tw {tw}, sample {i}: {ec:e} {es:e} > {bc:e} {bs:e}"
            );
            // Away from the saturation: the products' bound alone.
            for (e, x) in [(ec, th.cos()), (es, th.sin())] {
                if x < 1.0 - inner {
                    worst = worst.max(e / inner);
                } else {
                    worst_saturated = worst_saturated.max(e / bound(x));
                }
            }
        }
    }
    assert!(worst >= 0.5, "worst {worst} of the bound");
    assert!(worst_saturated >= 0.5, "saturated: worst {worst_saturated}");
}

/// The pair sums and the reference's Gram sums equal straightforward i64
/// sums of the same counts and reference words, for every block length
/// up to 64 (runs of 16 and the remainder), counts anywhere in 0..=4095
/// (the i32 runs' worst case included: all 4095 against ±2¹⁵).
#[test]
fn integer_sums_are_exact() {
    let t = SineTable::<1024>::libm();
    let mut rng = Rng::new(11);
    for case in 0..400 {
        let len = case % (BLOCK + 1);
        let tw = (rng.uniform() * 2e9) as u32 + 1;
        let r = Reference::new(&t, (rng.uniform() * 4e9) as u32, tw, len);
        let pairs: Vec<(u16, u16)> = (0..len)
            .map(|_| match case % 3 {
                0 => (4095, 4095),
                _ => (
                    (rng.uniform() * 4096.0) as u16,
                    (rng.uniform() * 4096.0) as u16,
                ),
            })
            .collect();
        let got = PairSums::of(r.words(), &pairs);
        let (mut p, mut pc, mut ps) = ([0i64; 2], [0i64; 2], [0i64; 2]);
        let (mut c1, mut s1, mut cc, mut ss, mut cs) = (0i64, 0i64, 0i64, 0i64, 0i64);
        for (&w, &(x, z)) in r.words().iter().zip(&pairs) {
            let (c, s) = (
                i64::from(w as u16 as i16),
                i64::from((w >> 16) as u16 as i16),
            );
            for (k, v) in [i64::from(x), i64::from(z)].into_iter().enumerate() {
                p[k] += v;
                pc[k] += v * c;
                ps[k] += v * s;
            }
            c1 += c;
            s1 += s;
            cc += c * c;
            ss += s * s;
            cs += c * s;
        }
        assert_eq!((got.p, got.pc, got.ps), (p, pc, ps), "case {case}");
        let g = Gram::of(r.words());
        assert_eq!(
            (g.n as usize, g.c, g.s, g.cc, g.ss, g.cs),
            (len, c1, s1, cc, ss, cs)
        );
    }
}

/// The rail check: a pair is railed iff a count is 0 or 4095 (or above,
/// which the 12-bit converter cannot give), checked for every count of
/// either channel next to every kind of partner, alone and inside a block.
#[test]
fn the_rail_check_flags_exactly_the_rails() {
    let t = SineTable::<1024>::libm();
    let r = Reference::new(&t, 0, 85_899_346, BLOCK);
    let railed = |v: u16| v == 0 || v >= ADC_FULL_SCALE;
    for v in 0..=4200u16 {
        for partner in [0u16, 1, 2047, 4094, 4095] {
            for (x, z) in [(v, partner), (partner, v)] {
                let want = railed(x) || railed(z);
                let one = PairSums::of(&r.words()[..1], &[(x, z)]);
                assert_eq!(one.railed, want, "({x}, {z})");
                assert_eq!(any_railed(&[(x, z)]), want, "any_railed ({x}, {z})");
                // Inside a block of clean samples, at position 37.
                let mut block = vec![(1000u16, 3000u16); BLOCK];
                block[37] = (x, z);
                assert_eq!(
                    PairSums::of(r.words(), &block).railed,
                    want,
                    "({x}, {z}) in a block"
                );
                assert_eq!(any_railed(&block), want, "any_railed ({x}, {z}) in a block");
            }
        }
    }
}

/// A synthetic force pair `f_z = 30 − 12 cos θ`, `f_x = μ·30 + 5 cos(θ + 0.8)`
/// (calibrations 0.02 and 0.01 N/count with offsets), fed in blocks of 64
/// with drive-period wraps inside blocks (25.0013 samples per period), as
/// the device feeds it: μ, the means and both harmonics against the closed
/// form. Bounds: the window's one sample in ≈ 50 000 and the counts'
/// rounding (≤ 1e-3 of μ and the means); the harmonics' amplitude
/// additionally the reference's `√2·ε_r` (R2–R3, ≤ 1e-4) — within 5e-3, the
/// phases within 2e-3 rad. The same window fed one sample at a time gives
/// the same μ, means, samples and standard error to the bit (the block's
/// runs split exactly where the per-sample path sees the wraps).
#[test]
fn the_estimator_in_blocks_meets_the_closed_form() {
    let table = SineTable::<1024>::libm();
    let cx = Calibration {
        gain: 0.01,
        offset: 300.0,
    };
    let cz = Calibration {
        gain: 0.02,
        offset: 150.0,
    };
    let tw = (4_294_967_296.0 / 25.0013) as u32;
    let (fz0, fz1, mu, fx1, phx) = (30.0, 12.0, 0.27, 5.0, 0.8);
    let force = |th: f64| {
        let fz = fz0 - fz1 * th.cos();
        let fx = mu * fz0 + fx1 * (th + phx).cos();
        (
            (fx / 0.01 + 300.0).round() as u16,
            (fz / 0.02 + 150.0).round() as u16,
        )
    };
    let mut blocks = Estimator::new(cx, cz, ADC_FULL_SCALE).unwrap();
    let mut single = Estimator::new(cx, cz, ADC_FULL_SCALE).unwrap();
    blocks.start(500).unwrap();
    single.start(500).unwrap();
    let mut acc = 12_345u32;
    let mut closed = false;
    for _ in 0..2_000 {
        let samples: Vec<(u16, u16)> = (0..BLOCK as u32)
            .map(|i| force(phase_rad(acc.wrapping_add(i.wrapping_mul(tw)))))
            .collect();
        let r = Reference::new(&table, acc, tw, BLOCK);
        let at = blocks.push_block(r.words(), acc, tw, &samples);
        let mut one = None;
        for (i, &(x, z)) in samples.iter().enumerate() {
            let p = acc.wrapping_add((i as u32).wrapping_mul(tw));
            if single.push(&table, p, x, z) && one.is_none() {
                one = Some(i);
            }
        }
        assert_eq!(at, one, "the block and the samples close at the same index");
        acc = acc.wrapping_add((BLOCK as u32).wrapping_mul(tw));
        if at.is_some() {
            closed = true;
            break;
        }
    }
    assert!(closed, "the window did not close");
    let e = blocks.estimate().unwrap();
    // Everything but the harmonics is the same to the bit (the block's
    // runs split exactly where the per-sample path sees the wraps); the
    // harmonics differ by the two references' errors (the block's rotates
    // between seeds: R3), each within its bound of the closed form below.
    let s1 = single.estimate().unwrap();
    assert_eq!(
        (
            e.mu,
            e.fx_mean,
            e.fz_mean,
            e.samples,
            e.std_error,
            e.reasons
        ),
        (
            s1.mu,
            s1.fx_mean,
            s1.fz_mean,
            s1.samples,
            s1.std_error,
            s1.reasons
        )
    );
    for h in [s1.fx_h1, s1.fz_h1, e.fx_h1, e.fz_h1] {
        assert!(h.amplitude.is_finite() && h.phase.is_finite());
    }
    assert!((f64::from(s1.fx_h1.amplitude) - fx1).abs() <= 5e-3 * fx1);
    assert!((f64::from(s1.fz_h1.amplitude) - fz1).abs() <= 5e-3 * fz1);
    assert!((f64::from(e.mu) - mu).abs() <= 1e-3 * mu, "{e:?}");
    assert!((f64::from(e.fz_mean) - fz0).abs() <= 1e-3 * fz0);
    assert!(
        (f64::from(e.fz_h1.amplitude) - fz1).abs() <= 5e-3 * fz1,
        "{e:?}"
    );
    assert!((f64::from(e.fz_h1.phase).abs() - std::f64::consts::PI).abs() <= 2e-3);
    assert!((f64::from(e.fx_h1.amplitude) - fx1).abs() <= 5e-3 * fx1);
    assert!((f64::from(e.fx_h1.phase) - phx).abs() <= 2e-3);
    assert_eq!(e.periods, 500);
    assert!(
        (f64::from(e.samples) - 25.0013 * 500.0).abs() <= 1.0,
        "{}",
        e.samples
    );
    assert!(!e.saturated);
}

/// A reference holds the samples asked for, at most a block
/// (`Reference::new`'s documented cut): its length, its emptiness and its
/// words agree for 0, 1, a part, a whole block and more than one; forming
/// it again in place (`set`) takes the new length, and a cut reference's
/// words are a whole block's at the same start.
#[test]
fn a_reference_holds_the_samples_asked_for_at_most_a_block() {
    let t = SineTable::<1024>::libm();
    let (acc0, tw) = (123_456_789u32, 85_899_346u32);
    let whole = Reference::new(&t, acc0, tw, BLOCK);
    for (asked, held) in [
        (0, 0),
        (1, 1),
        (37, 37),
        (BLOCK, BLOCK),
        (BLOCK + 1, BLOCK),
        (1000, BLOCK),
    ] {
        let r = Reference::new(&t, acc0, tw, asked);
        assert_eq!(r.len(), held, "asked {asked}");
        assert_eq!(r.words().len(), held, "asked {asked}");
        assert_eq!(r.is_empty(), held == 0, "asked {asked}");
        assert_eq!(r.words(), &whole.words()[..held], "asked {asked}");
    }
    let mut r = Reference::new(&t, acc0, tw, 5);
    r.set(&t, acc0, tw, 0);
    assert!(r.is_empty());
    assert_eq!(r.len(), 0);
    r.set(&t, acc0, tw, 9);
    assert!(!r.is_empty() && r.len() == 9);
    assert!(Reference::EMPTY.is_empty());
    assert_eq!(Reference::EMPTY.len(), 0);
}
