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

/// The names of latched fault bits.
pub fn fault_names(bits: u32) -> Vec<String> {
    use board::device::faults::*;
    let known = [
        (ADC_SATURATED, "adc_saturated"),
        (DAC_UNDERRUN, "dac_underrun"),
        (WATCHDOG_RESET, "watchdog_reset"),
        (EXTERNAL, "external"),
        (ADC_OVERRUN, "adc_overrun"),
        (MEASURED_LIFTOFF, "measured_liftoff"),
        (LOSS_OF_LOCK, "loss_of_lock"),
        (PICKUP_OPEN, "pickup_open"),
        (SELF_TEST, "self_test"),
    ];
    let mut v: Vec<String> = known
        .iter()
        .filter(|(b, _)| bits & b != 0)
        .map(|(_, n)| (*n).to_string())
        .collect();
    let rest = bits & !known.iter().fold(0, |a, (b, _)| a | b);
    if rest != 0 {
        v.push(format!("0x{rest:x}"));
    }
    v
}
