//! The sample clock and its consumers: TIM2 at 500 kS/s, the dual DAC, and
//! the ADC pair (RM0090 §13, §14, §18).
//!
//! **Pins** (port A, §8.4.1): PA0 ADC1_IN0 (normal force), PA1 ADC2_IN1
//! (tangential force), PA4/PA5 DAC_OUT1/2 (normal and tangential
//! transducers), PA6 ADC1_IN6 and PA7 ADC2_IN7 (the motion pickups): analog
//! (MODER = 11). PA2/PA3 USART2 TX/RX: alternate function 7.
//!
//! **The order that loses no trigger.** TIM2's TRGO (MMS = 010, update)
//! paces both consumers. The prescaler is preloaded (§18.3.1) and takes
//! effect only at an update event, so the timer is loaded with UG
//! ([`load_sample_clock`]) *before* any consumer listens: the UG's TRGO
//! then reaches neither the DAC (TEN = 0) nor the ADC (EXTEN = 00). Then the
//! DAC is armed with its holding register preloaded ([`arm_dac`]), the ADCs
//! are powered and given their stabilisation time t_STAB = 3 µs (DS8626
//! Table 66) before their trigger can come ([`arm_adc`]), and only then
//! does the counter start ([`start_sample_clock`], which needs the
//! [`AdcReady`] that `arm_adc` returns). The first TRGO, one sample period
//! later, finds every consumer ready: the device's `adc_lag_samples = 1`
//! bookkeeping holds from the first tick.
//!
//! **DAC.** Both channels triggered by TIM2 TRGO (TSEL = 100), output
//! buffers on; only channel 1 requests DMA (DMAEN1): its one request per
//! trigger writes the packed DHR12RD word for both channels (§14.3.7). The
//! trigger moves DHR → DOR and only then requests the next word, so sample
//! k outputs word k − 1; DHR12RD is preloaded with the buffer's last word
//! (the one before word 0 in the circular order), so that the first trigger
//! outputs it and not 0. DMAUDRIE1: an underrun (a request not served
//! before the next trigger) raises the TIM6_DAC interrupt. The output
//! buffers are on: the outputs then swing 0.2 V … V_DDA − 0.2 V (DS8626
//! Table 65), so codes below ≈ 250 and above ≈ 3 845 are clipped (see
//! `docs/guide/bringup.md` for the calibration this asks for).
//!
//! **ADC pair.** Regular simultaneous mode (MULTI = 00110), DMA mode 2 (one
//! CDR word per pair of conversions), DDS = 1 (requests go on in circular
//! mode), ADCCLK = PCLK2/4 = 21 MHz (≤ 36 MHz, DS8626 Table 66). Each ADC
//! scans two channels per trigger (force, then pickup) with the shortest
//! sample time, 3 cycles: [`CONVERSION_CYCLES`] = 15 per conversion, so the
//! pickup is sampled [`PICKUP_DELAY_NS`] ≈ 714 ns after the force (the
//! device demodulates it at its own instant) and the scan takes 1.43 µs of
//! the 2 µs tick. OVRIE: an overrun (a conversion not taken by the DMA)
//! raises the ADC interrupt. The 3-cycle (143 ns) sample time needs a
//! low-impedance source with a charge reservoir at the pin: see
//! `docs/guide/bringup.md`.

use crate::buffers::HALF;
use crate::clocks::Clocks;
use crate::{Delay, Registers};

/// Sample rate, Hz (the device's `DeviceConfig::sample_rate_hz`).
pub const FS_HZ: u32 = 500_000;
/// ADC clock: PCLK2 / 4, Hz.
pub const ADC_CLOCK_HZ: u32 = Clocks::PLL.tim_apb2_hz / 2 / 4;
/// ADC sampling time, ADC clock cycles (SMP = 000).
pub const SAMPLE_CYCLES: u32 = 3;
/// One conversion: sampling + 12 cycles of successive approximation (§13.5).
pub const CONVERSION_CYCLES: u32 = SAMPLE_CYCLES + 12;
/// Conversions per ADC per trigger (force, pickup).
pub const SCAN_LENGTH: u32 = 2;
/// How long after the force sample each pickup is sampled, ns (rounded).
pub const PICKUP_DELAY_NS: u32 = ((CONVERSION_CYCLES as u64 * 1_000_000_000
    + ADC_CLOCK_HZ as u64 / 2)
    / ADC_CLOCK_HZ as u64) as u32;
/// ADC stabilisation time after ADON, µs (DS8626 Table 66: t_STAB ≤ 3 µs).
pub const ADC_STAB_US: u32 = 3;

// The scan fits the tick, and the ADC clock its limit.
const _: () = assert!(ADC_CLOCK_HZ <= 36_000_000);
const _: () =
    assert!((SCAN_LENGTH * CONVERSION_CYCLES) as u64 * FS_HZ as u64 <= ADC_CLOCK_HZ as u64);
// TIM2 divides its clock into whole sample periods.
const _: () = assert!(Clocks::PLL.tim_apb1_hz % FS_HZ == 0);
const _: () = assert!(HALF > 0);

/// Proof that the sample clock is loaded and not yet running.
#[derive(Debug)]
pub struct SampleClockLoaded(());

/// Proof that the ADCs are powered, stabilised and armed on TRGO.
#[derive(Debug)]
pub struct AdcReady(());

/// Clocks of the peripherals the sampling uses (RM0090 §6.3.10–13) and
/// the pins' modes (module docs).
pub fn enable_clocks_and_pins(r: &Registers) {
    r.rcc
        .ahb1enr()
        .modify(|_, w| w.gpioaen().enabled().dma1en().enabled().dma2en().enabled());
    r.rcc
        .apb1enr()
        .modify(|_, w| w.tim2en().enabled().usart2en().enabled().dacen().enabled());
    r.rcc
        .apb2enr()
        .modify(|_, w| w.adc1en().enabled().adc2en().enabled());
    r.gpioa.moder().modify(|_, w| {
        w.moder0()
            .analog()
            .moder1()
            .analog()
            .moder2()
            .alternate()
            .moder3()
            .alternate()
            .moder4()
            .analog()
            .moder5()
            .analog()
            .moder6()
            .analog()
            .moder7()
            .analog()
    });
    r.gpioa.afrl().modify(|_, w| w.afrl2().af7().afrl3().af7());
    link_rx_pull_up(r);
}

/// PA3 (USART2 RX) pulled up: an unconnected line reads idle, not noise.
pub fn link_rx_pull_up(r: &Registers) {
    r.gpioa.pupdr().modify(|_, w| w.pupdr3().pull_up());
}

/// TIM2 loaded for [`FS_HZ`] with TRGO on update, counter stopped (module
/// docs: the UG comes before any consumer listens).
pub fn load_sample_clock(r: &Registers, clocks: &Clocks) -> SampleClockLoaded {
    let t = r.tim2;
    t.cr1().write(|w| w.cen().disabled().urs().counter_only());
    t.psc().write(|w| w.psc().set(0));
    t.arr()
        .write(|w| w.arr().set(clocks.tim_apb1_hz / FS_HZ - 1));
    t.cr2().write(|w| w.mms().update());
    t.egr().write(|w| w.ug().update());
    t.cnt().write(|w| w.cnt().set(0));
    SampleClockLoaded(())
}

/// The DAC armed on TRGO with channel 1's DMA request, its outputs at
/// `preload` (the DAC buffer's last word; module docs). The channels are
/// enabled first without a trigger: then a write to DHR reaches DOR after
/// one APB1 cycle (RM0090 §14.3.4), so the outputs hold `preload` from
/// here until the first trigger, which outputs it again.
pub fn arm_dac(r: &Registers, preload: u32, _clock: &SampleClockLoaded) {
    r.dac.cr().write(|w| {
        w.en1()
            .enabled()
            .boff1()
            .enabled()
            .en2()
            .enabled()
            .boff2()
            .enabled()
    });
    r.dac.dhr12rd().write(|w| {
        w.dacc1dhr()
            .set((preload & 0xFFF) as u16)
            .dacc2dhr()
            .set(((preload >> 16) & 0xFFF) as u16)
    });
    r.dac.cr().write(|w| {
        w.en1()
            .enabled()
            .boff1()
            .enabled()
            .ten1()
            .enabled()
            .tsel1()
            .tim2trgo()
            .dmaen1()
            .enabled()
            .dmaudrie1()
            .enabled()
            .en2()
            .enabled()
            .boff2()
            .enabled()
            .ten2()
            .enabled()
            .tsel2()
            .tim2trgo()
    });
}

/// The ADC pair configured, powered and stabilised, armed on TRGO (module
/// docs). Waits [`ADC_STAB_US`].
pub fn arm_adc(
    r: &Registers,
    clocks: &Clocks,
    delay: &mut impl Delay,
    _clock: &SampleClockLoaded,
) -> AdcReady {
    r.adc_common.ccr().write(|w| {
        w.adcpre()
            .div4()
            .dma()
            .mode2()
            .dds()
            .continuous()
            .multi()
            .dual_r()
    });
    // Scans of two (L = 1): ADC1 IN0, IN6; ADC2 IN1, IN7.
    // SAFETY: channel numbers 0..=18, L 0..=15.
    r.adc1.sqr1().write(|w| unsafe { w.l().bits(1) });
    r.adc2.sqr1().write(|w| unsafe { w.l().bits(1) });
    r.adc1
        .sqr3()
        .write(|w| unsafe { w.sq1().bits(0).sq2().bits(6) });
    r.adc2
        .sqr3()
        .write(|w| unsafe { w.sq1().bits(1).sq2().bits(7) });
    r.adc1
        .smpr2()
        .write(|w| w.smp0().cycles3().smp6().cycles3());
    r.adc2
        .smpr2()
        .write(|w| w.smp1().cycles3().smp7().cycles3());
    r.adc1
        .cr1()
        .write(|w| w.scan().enabled().ovrie().enabled().res().twelve_bit());
    r.adc2
        .cr1()
        .write(|w| w.scan().enabled().ovrie().enabled().res().twelve_bit());
    r.adc2.cr2().write(|w| w.adon().enabled());
    r.adc1
        .cr2()
        .write(|w| w.adon().enabled().exten().rising_edge().extsel().tim2trgo());
    delay.wait_us(ADC_STAB_US, clocks.sysclk_hz);
    AdcReady(())
}

/// Starts TIM2: the first TRGO comes one sample period later.
pub fn start_sample_clock(r: &Registers, _adc: AdcReady) {
    r.tim2.cr1().modify(|_, w| w.cen().enabled());
}

/// Whether the DAC's DMA underran since the last call (DAC_SR.DMAUDR1,
/// cleared by writing 1, §14.5.14): channel 1 then stops requesting.
pub fn take_dac_underrun(r: &Registers) -> bool {
    let u = r.dac.sr().read().dmaudr1().bit_is_set();
    if u {
        r.dac.sr().write(|w| w.dmaudr1().set_bit());
    }
    u
}

/// Whether either ADC overran since the last call (ADC_SR.OVR, cleared by
/// writing 0, §13.13.1): the DMA then stops taking conversions.
pub fn take_adc_overrun(r: &Registers) -> bool {
    let mut any = false;
    for adc in [r.adc1, r.adc2] {
        if adc.sr().read().ovr().bit_is_set() {
            any = true;
            // rc_w0: the PAC's `write` sets the other flags' bits to 1,
            // which leaves them as they are.
            adc.sr().write(|w| w.ovr().clear());
        }
    }
    any
}

/// The DAC's safe state after its stream stopped or underran: DMA1
/// Stream5 disabled (waited for, at most [`STREAM_STOP_READS`] reads: a
/// request still pending from the underrun must not be served after the
/// rest word is written), channel 1's DMA request off, and `rest` (the
/// device's rest word: zero amplitude) in DHR12RD, which the running
/// trigger moves to the outputs within one sample.
pub fn hold_dac(r: &Registers, rest: u32) {
    let st = r.dma1.st(5);
    st.cr().modify(|_, w| w.en().disabled());
    for _ in 0..STREAM_STOP_READS {
        if st.cr().read().en().is_disabled() {
            break;
        }
    }
    r.dac.cr().modify(|_, w| w.dmaen1().disabled());
    r.dac.dhr12rd().write(|w| {
        w.dacc1dhr()
            .set((rest & 0xFFF) as u16)
            .dacc2dhr()
            .set(((rest >> 16) & 0xFFF) as u16)
    });
}

/// The most reads of a stream's EN bit after disabling it: a stream ends
/// its current single transfer within a few bus cycles (§10.3.17).
pub const STREAM_STOP_READS: u32 = 1_000;

/// Stops the sampling for good (a board that failed its self-test after the
/// sample clock started): TIM2 stopped, the DAC held at `rest`.
pub fn stop(r: &Registers, rest: u32) {
    r.tim2.cr1().modify(|_, w| w.cen().disabled());
    hold_dac(r, rest);
}
