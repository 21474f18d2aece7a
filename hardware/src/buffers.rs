//! The DMA buffers' lengths, all from one constant: the half-buffer of
//! [`HALF`] sample ticks (`board::device::HALF_BUFFER`). A stream's
//! NDTR is the length of the buffer it is given ([`DmaBuffer`]), and a
//! handler's half is half of that: nothing is counted twice, and the
//! assertions below fail the build if the pieces stop fitting.

/// Sample ticks per half-buffer (64: 128 µs at 500 kS/s).
pub const HALF: usize = board::device::HALF_BUFFER;
/// DAC words per tick: one packed DHR12RD word drives both channels.
pub const DAC_WORDS_PER_TICK: usize = 1;
/// ADC words per tick: the dual-mode scan gives two CDR words (the forces,
/// then the pickups).
pub const ADC_WORDS_PER_TICK: usize = 2;
/// The DAC buffer: two halves of [`HALF`] ticks.
pub const DAC_WORDS: usize = 2 * HALF * DAC_WORDS_PER_TICK;
/// The ADC buffer: two halves of [`HALF`] ticks.
pub const ADC_WORDS: usize = 2 * HALF * ADC_WORDS_PER_TICK;

// NDTR is 16 bits (RM0090 §10.5.6) and a circular double buffer needs an
// even count; both buffers cover the same ticks, so one ADC half-transfer
// comes with each DAC half-transfer.
const _: () = assert!(DAC_WORDS <= 0xFFFF && DAC_WORDS % 2 == 0);
const _: () = assert!(ADC_WORDS <= 0xFFFF && ADC_WORDS % 2 == 0);
const _: () = assert!(DAC_WORDS / DAC_WORDS_PER_TICK == ADC_WORDS / ADC_WORDS_PER_TICK);

/// A word buffer a DMA stream runs over: its bus address and length.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DmaBuffer {
    /// Address of the first word on the bus (SRAM1/2: CCM RAM is out of
    /// the DMA's reach).
    pub addr: u32,
    /// Length in 32-bit words: the stream's NDTR.
    pub words: u16,
}

impl DmaBuffer {
    /// The buffer of a static array (the firmware's).
    ///
    /// The address is the pointer's value, which on the 32-bit target is
    /// the bus address.
    pub fn of<const N: usize>(buf: &'static [u32; N]) -> Self {
        const { assert!(N <= 0xFFFF && N % 2 == 0) };
        DmaBuffer {
            addr: buf.as_ptr() as usize as u32,
            words: N as u16,
        }
    }

    /// The buffer at `ptr` (a raw pointer: no reference to memory a DMA
    /// stream may be writing is formed).
    pub fn of_ptr<const N: usize>(ptr: *const [u32; N]) -> Self {
        const { assert!(N <= 0xFFFF && N % 2 == 0) };
        DmaBuffer {
            addr: ptr as *const u32 as usize as u32,
            words: N as u16,
        }
    }

    /// Words per half: what a half/full-transfer event hands over.
    pub fn half_words(&self) -> u32 {
        u32::from(self.words) / 2
    }

    /// Whether `addr` lies in the buffer's words.
    pub fn contains(&self, addr: u32) -> bool {
        addr >= self.addr && addr < self.addr + 4 * u32::from(self.words)
    }
}
