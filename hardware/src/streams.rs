//! The two DMA streams (RM0090 §10) and their handlers' decisions.
//!
//! * **DAC**: DMA1 Stream5, channel 7 (DAC1 request, Table 42), memory →
//!   DHR12RD (both channels in one 32-bit word, §14.5.9), circular over
//!   [`crate::buffers::DAC_WORDS`] words: one word per sample tick.
//! * **ADC**: DMA2 Stream0, channel 0 (ADC1, Table 43), ADC_CDR (the pair's
//!   common data register, §13.13.18) → memory, circular over
//!   [`crate::buffers::ADC_WORDS`] words: two words per tick.
//!
//! Both: 32-bit on both sides, memory increment, half- and full-transfer
//! interrupts, and the transfer-error and direct-mode-error interrupts. A
//! transfer error (a bus error) disables the stream (§10.3.17); a
//! direct-mode error (a request before the previous transfer ended) leaves
//! it running but means a lost or repeated word. The handler treats both as
//! a stopped stream: a fault, and the outputs held at rest.
//! NDTR is the buffer's length ([`DmaBuffer::words`]); the handlers' half is
//! half of it ([`DmaBuffer::half_words`]).
//!
//! A handler reads its stream's flags once ([`take_dac_flags`],
//! [`take_adc_flags`]), clears exactly the flags it read (a flag raised
//! between the read and the clear stays for the next entry), and decides
//! with [`StreamFlags::event`]: a half to refill or read
//! ([`board::dma::half_event`]), or an error. The FIFO-error
//! flag is cleared and ignored: in direct mode (the reset state of
//! DMA_SxFCR, used here) memory → peripheral it reports a bus underrun with
//! no data lost (§10.3.18).

use board::dma::{half_event, HalfEvent};

use crate::buffers::DmaBuffer;
use crate::{pac, Registers};

/// DAC base address (RM0090 §2.3 memory map).
pub const DAC_BASE: u32 = 0x4000_7400;
/// DAC_DHR12RD: dual 12-bit right-aligned data holding register (§14.5.9).
pub const DAC_DHR12RD: u32 = DAC_BASE + 0x20;
/// ADC common registers base (ADC1 base 0x4001_2000 + 0x300).
pub const ADC_COMMON_BASE: u32 = 0x4001_2300;
/// ADC_CDR: the dual mode's common data register (§13.13.18).
pub const ADC_CDR: u32 = ADC_COMMON_BASE + 0x08;
/// DMA1 Stream5's channel for the DAC1 request (Table 42).
pub const DAC_CHANNEL: u8 = 7;
/// DMA2 Stream0's channel for the ADC1 request (Table 43).
pub const ADC_CHANNEL: u8 = 0;

/// A stream's interrupt flags as one handler entry read them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StreamFlags {
    /// Half transfer.
    pub ht: bool,
    /// Transfer complete (the buffer wrapped).
    pub tc: bool,
    /// Transfer error: a bus error; the stream disabled itself.
    pub te: bool,
    /// Direct-mode error: a request came before the previous transfer ended.
    pub dme: bool,
    /// FIFO error (ignored in direct mode).
    pub fe: bool,
    /// NDTR when the flags were read.
    pub ndtr: u16,
}

/// What a handler entry must do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StreamEvent {
    /// Refill (DAC) or read (ADC) this half.
    Half(HalfEvent),
    /// The stream stopped on an error (TE or DME): latch the fault and put
    /// the outputs in the safe state.
    Stopped,
    /// Nothing to do (a spurious or FIFO-only entry).
    None,
}

impl StreamFlags {
    /// The decision for a stream over `buf`: an error first (the data of a
    /// stopped stream is not to be used), then the half.
    pub fn event(&self, buf: &DmaBuffer) -> StreamEvent {
        if self.te || self.dme {
            return StreamEvent::Stopped;
        }
        match half_event(self.ht, self.tc, u32::from(self.ndtr), buf.half_words()) {
            Some(h) => StreamEvent::Half(h),
            None => StreamEvent::None,
        }
    }
}

type Stream = pac::dma2::ST;

/// Configures and enables a stream (`dir` memory → peripheral or back).
fn setup(st: &Stream, channel: u8, par: u32, buf: &DmaBuffer, to_peripheral: bool) {
    // A stream is reprogrammed only while disabled (§10.3.17); EN reads 0
    // once an ongoing transfer has ended (one word: immediate here, the
    // stream was never started, so no wait is needed after reset).
    st.cr().write(|w| w.en().disabled());
    // SAFETY: any 32-bit address is a valid PAR/M0AR value; NDTR is 16 bits.
    st.par().write(|w| unsafe { w.pa().bits(par) });
    st.m0ar().write(|w| unsafe { w.m0a().bits(buf.addr) });
    st.ndtr().write(|w| w.ndt().set(buf.words));
    st.cr().write(|w| {
        let w = w
            .chsel()
            .set(channel)
            .pl()
            .very_high()
            .msize()
            .bits32()
            .psize()
            .bits32()
            .minc()
            .incremented()
            .pinc()
            .fixed()
            .circ()
            .enabled()
            .tcie()
            .enabled()
            .htie()
            .enabled()
            .teie()
            .enabled()
            .dmeie()
            .enabled();
        if to_peripheral {
            w.dir().memory_to_peripheral()
        } else {
            w.dir().peripheral_to_memory()
        }
    });
    st.cr().modify(|_, w| w.en().enabled());
}

/// DMA1 Stream5 → DAC_DHR12RD over `buf` (module docs). The DAC itself is
/// armed by [`crate::sampling::arm_dac`].
pub fn setup_dac_stream(r: &Registers, buf: &DmaBuffer) {
    setup(r.dma1.st(5), DAC_CHANNEL, DAC_DHR12RD, buf, true);
}

/// DMA2 Stream0 ← ADC_CDR over `buf` (module docs).
pub fn setup_adc_stream(r: &Registers, buf: &DmaBuffer) {
    setup(r.dma2.st(0), ADC_CHANNEL, ADC_CDR, buf, false);
}

/// Whether a stream reads back the channel, addresses and length it was
/// given (the self-test's `dma_setup`; before the sample clock starts, so
/// NDTR has not moved).
fn reads_back(st: &Stream, channel: u8, par: u32, buf: &DmaBuffer) -> bool {
    let cr = st.cr().read();
    cr.chsel().bits() == channel
        && cr.en().is_enabled()
        && cr.circ().is_enabled()
        && st.par().read().pa().bits() == par
        && st.m0ar().read().m0a().bits() == buf.addr
        && st.ndtr().read().ndt().bits() == buf.words
}

/// Whether both streams read back the channel, addresses and length they
/// were given (the self-test's `dma_setup`).
pub fn streams_read_back(r: &Registers, dac: &DmaBuffer, adc: &DmaBuffer) -> bool {
    reads_back(r.dma1.st(5), DAC_CHANNEL, DAC_DHR12RD, dac)
        && reads_back(r.dma2.st(0), ADC_CHANNEL, ADC_CDR, adc)
}

/// DMA1 Stream5's flags (HISR bits 6–11), cleared as read (HIFCR).
pub fn take_dac_flags(r: &Registers) -> StreamFlags {
    let isr = r.dma1.hisr().read();
    let f = StreamFlags {
        ht: isr.htif5().bit_is_set(),
        tc: isr.tcif5().bit_is_set(),
        te: isr.teif5().bit_is_set(),
        dme: isr.dmeif5().bit_is_set(),
        fe: isr.feif5().bit_is_set(),
        ndtr: r.dma1.st(5).ndtr().read().ndt().bits(),
    };
    r.dma1.hifcr().write(|w| {
        w.chtif5()
            .bit(f.ht)
            .ctcif5()
            .bit(f.tc)
            .cteif5()
            .bit(f.te)
            .cdmeif5()
            .bit(f.dme)
            .cfeif5()
            .bit(f.fe)
    });
    f
}

/// DMA2 Stream0's flags (LISR bits 0–5), cleared as read (LIFCR).
pub fn take_adc_flags(r: &Registers) -> StreamFlags {
    let isr = r.dma2.lisr().read();
    let f = StreamFlags {
        ht: isr.htif0().bit_is_set(),
        tc: isr.tcif0().bit_is_set(),
        te: isr.teif0().bit_is_set(),
        dme: isr.dmeif0().bit_is_set(),
        fe: isr.feif0().bit_is_set(),
        ndtr: r.dma2.st(0).ndtr().read().ndt().bits(),
    };
    r.dma2.lifcr().write(|w| {
        w.chtif0()
            .bit(f.ht)
            .ctcif0()
            .bit(f.tc)
            .cteif0()
            .bit(f.te)
            .cdmeif0()
            .bit(f.dme)
            .cfeif0()
            .bit(f.fe)
    });
    f
}
