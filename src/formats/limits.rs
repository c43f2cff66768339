//! The memory limit for loading: a safe fraction of physical memory by default.

/// Physical memory in bytes, from `/proc/meminfo` where there is one, else `None`.
#[must_use]
pub fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Half of physical memory (4 GiB when it cannot be read): room for the volume and the work on it.
#[must_use]
pub fn default_max_memory() -> u64 {
    physical_memory().map_or(4 << 30, |m| m / 2)
}

/// Parses a byte count such as `512M`, `4G`, `1.5GiB`, `2TB` or `1048576` (binary units).
#[must_use]
pub fn parse_bytes(text: &str) -> Option<u64> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let value: f64 = num.parse().ok()?;
    let shift = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        _ => return None,
    };
    let bytes = value * (1u64 << shift) as f64;
    (bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64).then_some(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_units() {
        assert_eq!(parse_bytes("1048576"), Some(1 << 20));
        assert_eq!(parse_bytes("512M"), Some(512 << 20));
        assert_eq!(parse_bytes("1.5GiB"), Some(3 << 29));
        assert_eq!(parse_bytes("2 tb"), Some(2 << 40));
        assert_eq!(parse_bytes("0"), None);
        assert_eq!(parse_bytes("12 apples"), None);
        assert_eq!(parse_bytes(""), None);
    }

    #[test]
    fn default_is_below_physical_memory() {
        if let Some(m) = physical_memory() {
            assert_eq!(default_max_memory(), m / 2);
        }
    }
}
