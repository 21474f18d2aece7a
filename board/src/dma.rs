//! Which half of a circular double buffer a DMA half/full-transfer interrupt
//! hands over, and whether the handler was late — the decision the
//! firmware's DAC and ADC handlers make, free of registers so that it is
//! tested natively.
//!
//! A stream runs circularly over `2·half_len` items; its NDTR counts the
//! items left in the current pass, from `2·half_len` down to 1. The
//! half-transfer flag (HT) is raised when the stream leaves the first half,
//! the transfer-complete flag (TC) when it leaves the second (RM0090 §10.3.11).
//! The handler clears both flags each time it runs, so between two runs the
//! events alternate HT, TC, HT, …:
//! * one flag set — the usual case: the stream has just left the half the
//!   flag names (HT → half 0, TC → half 1), which is now free;
//! * both flags set — the handler missed an event (it is late by at least a
//!   half-buffer): the flags no longer tell which event came last, but NDTR
//!   does: the free half is the one the stream is *not* in. The half it
//!   missed was overwritten (ADC) or output stale (DAC): a fault;
//! * no flag — a spurious entry (e.g. an error flag): nothing to do.

/// A half handed over by a DMA interrupt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HalfEvent {
    /// The half (0 or 1) the stream has left: the one to refill (DAC) or
    /// read (ADC).
    pub half: usize,
    /// Both flags were set: the handler was late by at least a half.
    pub late: bool,
}

/// The half handed over, from the flags read at the handler's entry and the
/// stream's NDTR (items left in the pass, `1..=2·half_len`); `None` for an
/// entry with neither flag.
pub fn half_event(ht: bool, tc: bool, ndtr: u32, half_len: u32) -> Option<HalfEvent> {
    let half = match (ht, tc) {
        (false, false) => return None,
        (true, false) => 0,
        (false, true) => 1,
        // Late: the stream is in the first half while NDTR > half_len, so
        // the second half is the one it left last, and vice versa.
        (true, true) => usize::from(ndtr > half_len),
    };
    Some(HalfEvent {
        half,
        late: ht && tc,
    })
}
