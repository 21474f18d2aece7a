//! Cost of one model prediction on the Cortex-M4F (f32, exact solver), for
//! QEMU: `qemu-system-arm -machine netduinoplus2 -icount shift=0 … -kernel predict_cost`.
//! With `-icount shift=0` each instruction advances virtual time by 1 ns, and
//! SysTick counts virtual time at the core clock; a block of exactly 1000
//! `nop`s calibrates ticks per instruction. Prints instruction counts through
//! semihosting and exits with status 0. (QEMU has no DWT cycle counter, and
//! its instruction count ignores pipeline and flash wait states: on the chip a
//! cycle count is ≈ 1–1.5× this.)
#![no_std]
#![no_main]

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use defmt_rtt as _;
use model_core::device;
use model_core::{Scene, SceneParams};
use panic_probe as _;
// Link the device crate for its interrupt vector table.
use stm32f4 as _;

fn ticks(f: impl FnOnce()) -> u32 {
    let t0 = SYST::get_current();
    f();
    let t1 = SYST::get_current();
    t0.wrapping_sub(t1) & 0x00FF_FFFF
}

/// Exactly 1000 `nop`s (in their own function, so no literal pool spans them).
#[inline(never)]
fn nops_1000() {
    // SAFETY: `nop` has no effect.
    unsafe { core::arch::asm!(".rept 1000", "nop", ".endr", options(nomem, nostack)) }
}

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        debug::exit(debug::EXIT_FAILURE);
        loop {
            cortex_m::asm::wfi();
        }
    };
    let mut syst = cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(0x00FF_FFFF);
    syst.clear_current();
    syst.enable_counter();

    // Calibration: exactly 1000 instructions.
    let cal = ticks(nops_1000);
    let empty = ticks(|| {});
    let per_insn = (cal.saturating_sub(empty)) as f32 / 1000.0;
    hprintln!(
        "calibration: {} ticks / 1000 nop ({} per instruction)",
        cal - empty,
        per_insn
    );

    let scene = match Scene::<f32>::new(SceneParams {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
        uz0: 4e-6,
        duz: 2e-6,
        dux: 0.3e-6,
        omega: 2.0 * core::f32::consts::PI * 20e3,
        phi: 0.7,
    }) {
        Ok(s) => s,
        Err(_) => {
            debug::exit(debug::EXIT_FAILURE);
            loop {
                cortex_m::asm::wfi();
            }
        }
    };
    let vc = model_core::analytic::CriticalVelocity::of(&scene);
    let mut worst = 0u32;
    let mut sum = 0u32;
    let n = 16;
    for i in 0..n {
        let x = -0.95 + 1.9 * (i as f32 + 0.5) / n as f32;
        let v = x * if x > 0.0 { vc.forward } else { vc.backward };
        let mut out = None;
        let t = ticks(|| out = Some(device::predict(&scene, v))).saturating_sub(empty);
        if !matches!(out, Some(Ok(_))) {
            debug::exit(debug::EXIT_FAILURE);
        }
        let insn = (t as f32 / per_insn) as u32;
        worst = worst.max(insn);
        sum += insn;
    }
    hprintln!(
        "predict (f32 exact, 16 velocities in (-v_c, v_c)): mean {} instructions, worst {}",
        sum / n,
        worst
    );
    let mut r = None;
    let t = ticks(|| r = Some(device::regime(&scene))).saturating_sub(empty);
    hprintln!(
        "regime classification: {} instructions",
        (t as f32 / per_insn) as u32
    );

    // DDS refill of one 256-sample half-buffer (two channels, packed words),
    // and building the 1024-entry table with libm and with micromath.
    use model_core::dds::{Dds, Level, SineTable, Slew};
    let mut tl = None;
    let t_libm = ticks(|| tl = Some(SineTable::<1024>::libm())).saturating_sub(empty);
    let mut tm = None;
    let t_mm = ticks(|| tm = Some(core::hint::black_box(SineTable::<1024>::micromath())))
        .saturating_sub(empty);
    core::hint::black_box(&tm);
    hprintln!(
        "sine table N=1024 build: libm {} instructions, micromath {}",
        (t_libm as f32 / per_insn) as u32,
        (t_mm as f32 / per_insn) as u32
    );
    if let Some(table) = tl.as_ref() {
        let slew = Slew {
            amp_per_sample: 1.0,
            dc_per_sample: 1.0,
            phase_per_sample: 1 << 20,
        };
        if let Ok(mut dds) = Dds::new(table, 1e6, slew) {
            let _ = dds.set_frequency(40_000.0);
            let _ = dds.set_level(
                0,
                Level {
                    amp: 1000.0,
                    dc: 2048.0,
                },
            );
            let _ = dds.set_level(
                1,
                Level {
                    amp: 1000.0,
                    dc: 2048.0,
                },
            );
            let mut buf = [0u32; 256];
            let t = ticks(|| dds.fill(&mut buf)).saturating_sub(empty);
            hprintln!(
                "DDS fill while ramping: {} instructions per sample (both channels)",
                (t as f32 / per_insn / 256.0) as u32
            );
            while !dds.settled() {
                dds.fill(&mut buf);
            }
            let t = ticks(|| dds.fill(&mut buf)).saturating_sub(empty);
            hprintln!(
                "DDS fill, settled: {} instructions per sample (both channels)",
                (t as f32 / per_insn / 256.0) as u32
            );
            dds.set_interp(model_core::dds::Interp::Nearest);
            let t = ticks(|| dds.fill(&mut buf)).saturating_sub(empty);
            hprintln!(
                "DDS fill, settled, nearest entry: {} instructions per sample (both channels)",
                (t as f32 / per_insn / 256.0) as u32
            );
            core::hint::black_box(&buf);
        }
    }
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}
