//! One reference for every signal of an ADC block (issue 35): the drive
//! phase's cosine and sine at each sample, formed once from the DDS's own
//! accumulator and table, and the sums the force estimator and the pickups'
//! lock-ins take against it, in integers, in one pass per signal pair.
//!
//! ```text
//! c_i = sat16(round(2¹⁵ cos θ_i)),  s_i = sat16(round(2¹⁵ sin θ_i))                 (R1)
//! θ_i = 2π (a₀ + i·tw)/2³²   (the accumulator of sample i, ADC lag included)
//! ```
//!
//! The table read of eq. (Q1) ([`crate::dds::SineTable::cos_sin_q30`], Q30)
//! gives the first sample's phase of every run of [`RUN`] samples,
//! `T = (cos θ_r, sin θ_r)`, and, once per tuning word ([`RunSteps`]), the
//! run's steps `E_b = (cos bΔ, sin bΔ)`, `b < RUN`, `Δ = 2π·tw/2³²`, read at
//! the exact phase words `b·tw`. Each sample is the complex product
//!
//! ```text
//! c = ⌊(T_c·E_c − T_s·E_s)/2³²⌉,  s = ⌊(T_s·E_c + T_c·E_s)/2³²⌉  (Q28)       (R3)
//! ```
//!
//! (four high-word multiplies, `SMMLA`/`SMMLS`, with the rounding constant
//! as the first one's addend), rounded to Q15 and saturated to 16 bits
//! (`+2¹⁵` becomes `2¹⁵ − 1`, one `SSAT`), packed as two i16 in one word
//! (`c` low, `s` high), so a pair of samples and its reference are two
//! loads. With `ε_s = ε_t + (2π/N)²/8 + 2⁻²⁹` the bound of each Q30 read
//! (the table, its interpolation, the halved product's floor), the error of
//! `c_i`, `s_i` against the exact cosine and sine is at most
//!
//! ```text
//! ε_r = 2√2·ε_s + 2ε_s² + 2⁻²⁷ + 2⁻¹⁶,  and max(ε_r, 2⁻¹⁵) where it saturates   (R2)
//! ```
//!
//! of 1: each product's factors within `ε_s` per component, so
//! `|Re((T − e^{iθ_r})·E_b)| ≤ ε_s(|cos bΔ| + |sin bΔ|) ≤ √2·ε_s`, the same
//! for `E_b`'s error and `2ε_s²` for both together; the two floors of the
//! high words (within 2⁻²⁷); the Q15 rounding (2⁻¹⁶); the clamp of `+2¹⁵`
//! to `2¹⁵ − 1` moves a value towards any true value below `1 − 2⁻¹⁵`, and
//! is at most 2⁻¹⁵ from one above. No error grows along the run: ≤ 3.06e-5
//! for any step at N = 1024 with the libm table (`tests/tests/reference.rs`).
//!
//! **The sums.** For a pair of signals `(x_i, z_i)` (ADC counts, `< 2¹²`):
//! `Σx`, `Σz` and `Σx·c`, `Σx·s`, `Σz·c`, `Σz·s`, exact. Each product is
//! below `4095·2¹⁵ < 2²⁷`, so sixteen of them fit an i32
//! (`16·4095·2¹⁵ = 2 146 959 360 < 2³¹`): the loop adds them in i32 over
//! runs of [`RUN`] samples and widens once per run. The reference's own sums
//! for the lock-ins' normal equations (`Σc`, `Σs`, `Σc²`, `Σs²`, `Σcs`,
//! [`Gram`]) are formed with the reference, once per block.
//!
//! Contexts: [`Reference::new`] and [`PairSums::of`] run in the ADC
//! handler (on the board, interrupt priority `DSP`), once per block.

use super::dds::SineTable;

/// The most samples of one block's reference (the board's ADC half-buffer).
pub const BLOCK: usize = 64;

/// Samples added in i32 before the sums widen to i64 (module docs).
pub const RUN: usize = 16;

/// `round(2¹⁵·v/2³⁰)` of a Q30 value, with `+2¹⁵` clamped to `2¹⁵ − 1` (R1;
/// a saturation to 16 bits, one `SSAT` on the M4).
#[inline(always)]
fn q15(v: i32) -> i32 {
    ((v + (1 << 14)) >> 15).clamp(i32::from(i16::MIN), i32::from(i16::MAX))
}

/// The Q15 cosine and sine (R1) of phase word `p`, packed: `c` in the low
/// half, `s` in the high half.
#[inline(always)]
pub fn packed<const N: usize>(t: &SineTable<N>, p: u32) -> u32 {
    let (c, s) = t.cos_sin_q30(p);
    (q15(c) as u16 as u32) | ((q15(s) as u16 as u32) << 16)
}

/// The steps of a run at one tuning word (eq. R3): `E_b = (cos bΔ, sin bΔ)`
/// in Q30 for `b < RUN`, read from the table at the exact phase words
/// `b·tw` (`E_0 = (2³⁰, 0)`, exact). Formed when the tuning word changes
/// (15 table reads), not per fill.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RunSteps {
    tw: u32,
    e: [(i32, i32); RUN],
}

impl RunSteps {
    /// The steps of tuning word `tw` on table `t`.
    pub fn new<const N: usize>(t: &SineTable<N>, tw: u32) -> Self {
        let mut e = [(1 << 30, 0); RUN];
        for (b, x) in e.iter_mut().enumerate().skip(1) {
            *x = t.cos_sin_q30(tw.wrapping_mul(b as u32));
        }
        RunSteps { tw, e }
    }
}

/// Fills `out` with the packed reference words (R1) of the phases
/// `acc0 + i·tw`: each run of [`RUN`] samples the product (R3) of its first
/// phase, read from the table (eq. Q1, Q30), with the run's steps.
pub fn fill<const N: usize>(t: &SineTable<N>, acc0: u32, tw: u32, out: &mut [u32]) {
    fill_steps(t, acc0, &RunSteps::new(t, tw), out);
}

/// [`fill`] with the steps formed by the caller (the DDS keeps them per
/// tuning word: 15 table reads per retune, not per fill).
pub fn fill_steps<const N: usize>(t: &SineTable<N>, acc0: u32, steps: &RunSteps, out: &mut [u32]) {
    // `acc ± ⌊a·b/2³²⌋`-like high words (`SMMLA`, `SMMLS`: the 64-bit
    // `acc·2³² ± a·b`, its high word): Q30 × Q30 / 2³² is Q28. With the
    // rounding constant as the first addend, each component is the exact
    // value plus two floors, within (−2, 0] units of Q28 (eq. R2's 2⁻²⁷).
    let mla = |acc: i32, a: i32, b: i32| {
        (((i64::from(acc) << 32) + i64::from(a) * i64::from(b)) >> 32) as i32
    };
    let mls = |acc: i32, a: i32, b: i32| {
        (((i64::from(acc) << 32) - i64::from(a) * i64::from(b)) >> 32) as i32
    };
    // Q28 to Q15, the rounding constant already added: `>> 13`, saturated
    // (`SSAT #16, ASR #13`).
    let q15_of_q28 = |x: i32| (x >> 13).clamp(i32::from(i16::MIN), i32::from(i16::MAX));
    // Opaque to the optimiser, so that it stays the first multiply's
    // addend instead of an add per component after it.
    let half = core::hint::black_box(1i32 << 12);
    let tw = steps.tw;
    let mut acc = acc0;
    for run in out.chunks_mut(RUN) {
        let (tc, ts) = t.cos_sin_q30(acc);
        for (w, &(ec, es)) in run.iter_mut().zip(&steps.e) {
            let c = mls(mla(half, tc, ec), ts, es);
            let s = mla(mla(half, ts, ec), tc, es);
            *w = (q15_of_q28(c) as u16 as u32) | ((q15_of_q28(s) as u16 as u32) << 16);
        }
        acc = acc.wrapping_add(tw.wrapping_mul(run.len() as u32));
    }
}

/// The cosine (low half) of a packed reference word, Q15.
#[inline(always)]
pub fn cos_of(w: u32) -> i32 {
    i32::from(w as u16 as i16)
}

/// The sine (high half) of a packed reference word, Q15.
#[inline(always)]
pub fn sin_of(w: u32) -> i32 {
    (w as i32) >> 16
}

/// The reference's sums over samples: `n`, `Σc`, `Σs`, `Σc²`, `Σs²`,
/// `Σcs` (the normal equations' reference part, eq. L2 of
/// [`crate::lockin`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Gram {
    /// Samples.
    pub n: u32,
    /// Σc.
    pub c: i64,
    /// Σs.
    pub s: i64,
    /// Σc².
    pub cc: i64,
    /// Σs².
    pub ss: i64,
    /// Σcs.
    pub cs: i64,
}

impl Gram {
    /// The sums of the packed reference words `w`: each square and product
    /// a widening multiply-accumulate (`SMLAL` on the M4, 10 instructions
    /// per word), in a function of its own so that the loop keeps its
    /// accumulators in registers wherever it is called from.
    #[inline(never)]
    pub fn of(w: &[u32]) -> Self {
        let (mut c1, mut s1) = (0i32, 0i32);
        let (mut cc, mut ss, mut cs) = (0i64, 0i64, 0i64);
        for &r in w {
            let (c, s) = (cos_of(r), sin_of(r));
            c1 += c;
            s1 += s;
            cc += i64::from(c) * i64::from(c);
            ss += i64::from(s) * i64::from(s);
            cs += i64::from(c) * i64::from(s);
        }
        Gram {
            n: w.len() as u32,
            c: i64::from(c1),
            s: i64::from(s1),
            cc,
            ss,
            cs,
        }
    }
}

/// One block's reference (R1) and its [`Gram`] sums.
#[derive(Debug, Clone, Copy)]
pub struct Reference {
    words: [u32; BLOCK],
    len: usize,
}

impl Reference {
    /// No samples (a buffer for [`Reference::set`]).
    pub const EMPTY: Reference = Reference {
        words: [0; BLOCK],
        len: 0,
    };

    /// The reference of `len ≤ BLOCK` samples from phase word `acc0`,
    /// `tw` words per sample (more than [`BLOCK`] are cut to it).
    pub fn new<const N: usize>(t: &SineTable<N>, acc0: u32, tw: u32, len: usize) -> Self {
        let mut r = Reference {
            words: [0; BLOCK],
            len: 0,
        };
        r.set(t, acc0, tw, len);
        r
    }

    /// Forms the reference again in place (as [`Reference::new`]).
    pub fn set<const N: usize>(&mut self, t: &SineTable<N>, acc0: u32, tw: u32, len: usize) {
        self.len = len.min(BLOCK);
        fill(t, acc0, tw, &mut self.words[..self.len]);
    }

    /// The packed words (R1), one per sample.
    pub fn words(&self) -> &[u32] {
        &self.words[..self.len]
    }

    /// Samples.
    pub fn len(&self) -> usize {
        self.len
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// The sums of a pair of signals `(x, z)` against a reference: `Σx`, `Σz`,
/// `Σx·c`, `Σx·s`, `Σz·c`, `Σz·s` (module docs), exact for counts of the
/// 12-bit converters (`≤ ADC_FULL_SCALE`), and whether a sample sat at a
/// rail (0 or [`ADC_FULL_SCALE`]; a count above it, which a 12-bit
/// converter cannot give, counts as railed too, and the sums of its run
/// are then not exact).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PairSums {
    /// Σx, Σz.
    pub p: [i64; 2],
    /// Σx·c, Σz·c.
    pub pc: [i64; 2],
    /// Σx·s, Σz·s.
    pub ps: [i64; 2],
    /// A sample of either signal was 0 or ≥ [`ADC_FULL_SCALE`].
    pub railed: bool,
}

/// The full scale of the board's 12-bit converters, counts (the rail).
pub const ADC_FULL_SCALE: u16 = 4095;

impl PairSums {
    /// The sums of `pairs` against the reference words `w` (as many as
    /// `pairs`; extra ones of either are ignored).
    pub fn of(w: &[u32], pairs: &[(u16, u16)]) -> Self {
        let mut out = PairSums::default();
        let mut rails = 0u32;
        for (w, pairs) in w.chunks(RUN).zip(pairs.chunks(RUN)) {
            let r = run(w, pairs);
            // The packed sum's halves: Σx below, Σz above (module docs).
            out.p[0] += i64::from(r.xz & 0xFFFF);
            out.p[1] += i64::from(r.xz >> 16);
            out.pc[0] += i64::from(r.xc);
            out.ps[0] += i64::from(r.xs);
            out.pc[1] += i64::from(r.zc);
            out.ps[1] += i64::from(r.zs);
            rails |= r.rails;
        }
        out.railed = rails & RAIL_BITS != 0;
        out
    }
}

/// A sample pair as the DMA packs it: `x` in the low half, `z` in the
/// high half.
#[inline(always)]
fn packed_pair(x: u16, z: u16) -> u32 {
    u32::from(x) | (u32::from(z) << 16)
}

/// Whether a sample of `pairs` sat at a rail (a count 0 or ≥
/// [`ADC_FULL_SCALE`]): [`PairSums::of`]'s `railed` without the sums, one
/// packed word per pair (`RAIL_BITS`; ≈ 7 instructions a pair on the M4
/// against ≈ 15 for the four comparisons). The closed μ loop checks every
/// block with it, including the samples its estimates leave out.
pub fn any_railed(pairs: &[(u16, u16)]) -> bool {
    let mut rails = 0u32;
    for &(x, z) in pairs {
        rails |= rail_word(packed_pair(x, z));
    }
    rails & RAIL_BITS != 0
}

/// The bits of a run's `rails` that only a railed sample sets: for a pair
/// packed `w = x | z << 16` with `1 ≤ x, z ≤ 4094`, `(w + 0x1_0001) |
/// (w − 0x1_0001)` keeps each half within 12 bits; `x = 4095` carries into
/// bit 12 (`z`: 28), `x = 0` borrows through bits 12–15 (`z = 0`: 28–31),
/// and a count above 4095 has a bit above 11 of its own.
const RAIL_BITS: u32 = 0xF000_F000;

/// A packed pair's rail word: only a railed sample sets one of its
/// [`RAIL_BITS`].
#[inline(always)]
fn rail_word(p: u32) -> u32 {
    p.wrapping_add(0x1_0001) | p.wrapping_sub(0x1_0001)
}

/// One run's sums in i32 (at most [`RUN`] samples: module docs).
struct Run {
    /// `Σ(x | z << 16)`: over at most 16 counts below 2¹² each half's sum
    /// stays below 2¹⁶ (≤ 65 520), so the halves are `Σx` and `Σz` (a
    /// count above 4095 is railed, and its run's sums are not exact).
    xz: u32,
    xc: i32,
    xs: i32,
    zc: i32,
    zs: i32,
    /// The OR of each pair's rail word ([`RAIL_BITS`]).
    rails: u32,
}

/// The sums of one run of at most [`RUN`] samples, in registers (a
/// function of its own: the i64 totals of [`PairSums::of`] stay out of the
/// loop's registers). Each pair is packed into one word as the DMA delivers
/// it, so that the four products are the M4's 16-bit multiply-accumulates
/// (`SMLAxy`; the counts are below 2¹⁵, so as i16 they are unchanged).
#[inline(never)]
fn run(w: &[u32], pairs: &[(u16, u16)]) -> Run {
    let mut o = Run {
        xz: 0,
        xc: 0,
        xs: 0,
        zc: 0,
        zs: 0,
        rails: 0,
    };
    for (&r, &(x, z)) in w.iter().zip(pairs) {
        let p = packed_pair(x, z);
        let (c, s) = (cos_of(r), sin_of(r));
        let (x, z) = (i32::from(p as u16 as i16), (p as i32) >> 16);
        o.rails |= rail_word(p);
        o.xz = o.xz.wrapping_add(p);
        o.xc = o.xc.wrapping_add(x * c);
        o.xs = o.xs.wrapping_add(x * s);
        o.zc = o.zc.wrapping_add(z * c);
        o.zs = o.zs.wrapping_add(z * s);
    }
    o
}
