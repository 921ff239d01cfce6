//! What the machine offers, read from the operating system: its memory. Numerics that must
//! fit the machine (the weights' direct factorisation) and the size estimate of a case
//! ([`crate::budget`]) both read it here, so neither depends on the other.

/// The machine's memory from `/proc/meminfo`, bytes (None where it cannot be read).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Memory {
    /// `MemAvailable`, bytes.
    pub available: Option<f64>,
    /// `MemTotal`, bytes.
    pub total: Option<f64>,
}

impl Memory {
    /// Reads `/proc/meminfo` (Linux); elsewhere both are None.
    pub fn of_machine() -> Memory {
        let text = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
        let field = |name: &str| {
            text.lines()
                .find_map(|l| l.strip_prefix(name))
                .and_then(|rest| {
                    rest.trim()
                        .trim_end_matches("kB")
                        .trim()
                        .parse::<f64>()
                        .ok()
                })
                .map(|kb| kb * 1024.0)
        };
        Memory {
            available: field("MemAvailable:"),
            total: field("MemTotal:"),
        }
    }
}
