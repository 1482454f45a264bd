//! Rust names from DBC names: `FINGER_SETPOINT` -> `FingerSetpoint`, `LeadOffMask` ->
//! `lead_off_mask`.

/// UpperCamelCase for types and enum variants; ALL_CAPS words are tamed, existing CamelCase
/// is kept, and a leading digit gets a `V` prefix.
pub fn camel(name: &str) -> String {
    let mut out = String::new();
    for part in name.split(['_', ' ', '-']) {
        let mut chars = part.chars();
        if let Some(c) = chars.next() {
            out.push(c.to_ascii_uppercase());
            let rest: String = chars.collect();
            if part.chars().all(|c| !c.is_ascii_lowercase()) {
                out.push_str(&rest.to_ascii_lowercase());
            } else {
                out.push_str(&rest);
            }
        }
    }
    if out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, 'V');
    }
    out
}

/// snake_case for fields and methods; Rust keywords get a trailing `_`.
pub fn snake(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::new();
    for (i, &c) in chars.iter().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 && !out.ends_with('_') && word_starts(&chars, i) {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else if c == '-' || c == ' ' {
            out.push('_');
        } else {
            out.push(c);
        }
    }
    match out.as_str() {
        "type" | "match" | "mod" | "ref" | "self" | "fn" | "use" | "loop" | "move" => {
            format!("{out}_")
        }
        _ => out,
    }
}

/// Whether the uppercase letter at `i` (> 0) starts a new word: after a lowercase letter or a
/// digit, or as the last capital of an acronym followed by lowercase (`CRCValue` -> `crc_value`).
fn word_starts(chars: &[char], i: usize) -> bool {
    let prev = chars[i - 1];
    let next_lower = chars.get(i + 1).is_some_and(|n| n.is_ascii_lowercase());
    prev.is_ascii_lowercase() || prev.is_ascii_digit() || (prev.is_ascii_uppercase() && next_lower)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_rust_conventions() {
        assert_eq!(camel("FINGER_SETPOINT"), "FingerSetpoint");
        assert_eq!(camel("SR_500_HZ"), "Sr500Hz");
        assert_eq!(camel("500_HZ"), "V500Hz");
        assert_eq!(snake("LeadOffMask"), "lead_off_mask");
        assert_eq!(snake("Emg10"), "emg10");
        assert_eq!(snake("CRCValue"), "crc_value");
        assert_eq!(snake("Type"), "type_");
    }
}
