//! Quantities with units, as written in terrain specs (`5cm`, `2m`, `0.5kg`).
//!
//! Units are converted to SI exactly once, here. Printing goes the other way
//! and is exact: [`format_length`] picks `cm` only when the printed number
//! parses back to the very same `f64`.

/// A unit of length accepted in specs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    /// metres
    M,
    /// centimetres
    Cm,
    /// millimetres
    Mm,
}

impl LengthUnit {
    /// Parses a unit suffix (`m`, `cm`, `mm`).
    pub fn parse(suffix: &str) -> Option<Self> {
        match suffix {
            "m" => Some(Self::M),
            "cm" => Some(Self::Cm),
            "mm" => Some(Self::Mm),
            _ => None,
        }
    }

    /// Converts a number in this unit to metres.
    pub fn to_m(self, value: f64) -> f64 {
        match self {
            Self::M => value,
            Self::Cm => value / 100.0,
            Self::Mm => value / 1000.0,
        }
    }
}

/// Splits `"12.5cm"` into `("12.5", "cm")`: the number is the longest
/// prefix made of digits, `.`, signs and exponent markers.
pub fn split_number_unit(text: &str) -> (&str, &str) {
    let text = text.trim();
    let at = text
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '+' | '-' | 'e' | 'E')))
        .unwrap_or(text.len());
    let (number, unit) = text.split_at(at);
    (number, unit.trim())
}

/// Parses a plain number, rejecting NaN and infinities.
pub fn parse_finite(number: &str) -> Result<f64, String> {
    if number.is_empty() {
        return Err("no number".to_string());
    }
    let value: f64 = number
        .parse()
        .map_err(|_| format!("{number:?} is not a number"))?;
    if !value.is_finite() {
        return Err(format!("{number:?} is not a finite number"));
    }
    Ok(value)
}

/// Parses a length with a mandatory unit (`5cm`, `0.05m`, `50mm`) into metres.
pub fn parse_length_m(text: &str) -> Result<f64, String> {
    let (number, unit) = split_number_unit(text);
    let value = parse_finite(number)?;
    if unit.is_empty() {
        return Err(format!(
            "{text:?} has no unit (write m, cm or mm, e.g. \"{text}cm\")"
        ));
    }
    let unit = LengthUnit::parse(unit)
        .ok_or_else(|| format!("{text:?} has unknown unit {unit:?} (known: m, cm, mm)"))?;
    Ok(unit.to_m(value))
}

/// Parses a mass with a mandatory unit (`25kg`, `500g`) into kilograms.
pub fn parse_mass_kg(text: &str) -> Result<f64, String> {
    let (number, unit) = split_number_unit(text);
    let value = parse_finite(number)?;
    match unit {
        "kg" => Ok(value),
        "g" => Ok(value / 1000.0),
        "" => Err(format!("{text:?} has no unit (write kg or g)")),
        other => Err(format!(
            "{text:?} has unknown unit {other:?} (known: kg, g)"
        )),
    }
}

/// Prints a length so that [`parse_length_m`] reads back exactly the same
/// `f64`: in cm when that is exact, otherwise in metres, with the fewest
/// decimals that do (`3.5cm`, not the `3.5000000000000004cm` of 0.035 x 100).
pub fn format_length(value_m: f64) -> String {
    if value_m.abs() >= 1.0 {
        return format!("{value_m}m");
    }
    // the shortest decimal of value_m x per_m that reads back as value_m
    let shortest = |per_m: f64| {
        let scaled = value_m * per_m;
        (0..=17)
            .map(|decimals| format!("{scaled:.decimals$}"))
            .find(|text| text.parse::<f64>().map(|v| v / per_m) == Ok(value_m))
    };
    let mm = (value_m.abs() < 0.01)
        .then(|| shortest(1000.0).map(|mm| format!("{mm}mm")))
        .flatten();
    let cm = shortest(100.0).map(|cm| format!("{cm}cm"));
    // below 1 cm the shorter of the two, mm on a tie
    match (mm, cm) {
        (Some(mm), Some(cm)) if cm.len() < mm.len() => cm,
        (Some(mm), _) => mm,
        (None, Some(cm)) => cm,
        (None, None) => format!("{value_m}m"),
    }
}

/// Prints a mass in kg, exactly.
pub fn format_mass(value_kg: f64) -> String {
    format!("{value_kg}kg")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_convert_to_metres() {
        assert_eq!(parse_length_m("5cm"), Ok(0.05));
        assert_eq!(parse_length_m("50mm"), Ok(0.05));
        assert_eq!(parse_length_m("2m"), Ok(2.0));
        assert_eq!(parse_length_m("1.5e-2m"), Ok(0.015));
        assert!(parse_length_m("5").unwrap_err().contains("no unit"));
        assert!(
            parse_length_m("5xm")
                .unwrap_err()
                .contains("unknown unit \"xm\"")
        );
        assert!(parse_length_m("cm").unwrap_err().contains("no number"));
        assert!(parse_length_m("NaNcm").is_err());
        assert!(parse_length_m("infcm").is_err());
    }

    #[test]
    fn masses_convert_to_kilograms() {
        assert_eq!(parse_mass_kg("25.5kg"), Ok(25.5));
        assert_eq!(parse_mass_kg("500g"), Ok(0.5));
        assert!(parse_mass_kg("3").is_err());
    }

    #[test]
    fn printed_lengths_read_back_exactly() {
        for v in [
            0.05,
            0.02,
            2.0,
            20.0,
            0.2,
            0.001,
            0.123456789,
            1e-9,
            3.0,
            0.15,
            1.4,
        ] {
            let text = format_length(v);
            assert_eq!(parse_length_m(&text), Ok(v), "{v} printed as {text}");
        }
        assert_eq!(format_length(0.05), "5cm");
        assert_eq!(format_length(2.0), "2m");
        assert_eq!(format_length(0.2), "20cm");
        assert_eq!(format_length(0.002), "2mm");
        assert_eq!(format_length(1.5), "1.5m");
        // the fewest decimals that read back: 0.035 x 100 is 3.5000000000000004
        for text in ["3.5cm", "2.5cm", "0.7cm", "4.25cm", "1.5mm"] {
            assert_eq!(format_length(parse_length_m(text).unwrap()), text);
        }
    }
}
