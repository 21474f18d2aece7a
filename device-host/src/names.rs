//! The names of the device's bit sets, as text and JSON print them (one
//! implementation for `fricctl`, the benches and Python).

/// The names of the reason bits of an estimate.
pub fn reason_names(bits: u32) -> Vec<&'static str> {
    board::estimator::reasons::NAMES
        .iter()
        .filter(|(b, _)| bits & b != 0)
        .map(|(_, n)| *n)
        .collect()
}

/// Every fault bit with its name ([`board::device::faults`]), as `status`,
/// `Fault` telemetry and the view show them.
pub const FAULTS: [(u32, &str); 9] = {
    use board::device::faults::*;
    [
        (ADC_SATURATED, "adc_saturated"),
        (DAC_UNDERRUN, "dac_underrun"),
        (WATCHDOG_RESET, "watchdog_reset"),
        (EXTERNAL, "external"),
        (ADC_OVERRUN, "adc_overrun"),
        (MEASURED_LIFTOFF, "measured_liftoff"),
        (LOSS_OF_LOCK, "loss_of_lock"),
        (PICKUP_OPEN, "pickup_open"),
        (SELF_TEST, "self_test"),
    ]
};

/// The names of latched fault bits.
pub fn fault_names(bits: u32) -> Vec<String> {
    let mut v: Vec<String> = FAULTS
        .iter()
        .filter(|(b, _)| bits & b != 0)
        .map(|(_, n)| (*n).to_string())
        .collect();
    let rest = bits & !FAULTS.iter().fold(0, |a, (b, _)| a | b);
    if rest != 0 {
        v.push(format!("0x{rest:x}"));
    }
    v
}

/// The fault bit of a name of [`FAULTS`] (`external`), or of its number
/// (`8`); `None` for anything else.
pub fn fault_bit(text: &str) -> Option<u32> {
    let t = text.trim();
    FAULTS
        .iter()
        .find(|(b, n)| *n == t || t.parse::<u32>() == Ok(*b))
        .map(|(b, _)| *b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fault_bits_by_name_and_number() {
        assert_eq!(fault_bit("external"), Some(8));
        assert_eq!(fault_bit(" 16\n"), Some(16));
        assert_eq!(fault_bit("dac_underrun"), Some(2));
        assert_eq!(fault_bit("3"), None);
        assert_eq!(fault_bit("fire"), None);
        assert_eq!(fault_names(8 | 4), vec!["watchdog_reset", "external"]);
    }
}
