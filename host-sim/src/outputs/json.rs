//! Numbers of JSON built by hand (`serde_json::json!`): an `f32` as the decimal it prints as.
//!
//! serde_json's `Value` holds an `f32` as the `f64` it converts to, so `0.9f32` comes out as
//! `0.8999999761581421`; a derived `Serialize` writes `0.9`. Every `f32` put into a `Value`
//! goes through [`Short`], so what `frames`, the maps and the live map write reads as what the
//! records said.

use serde_json::Value;

/// A number as the JSON of its shortest decimal.
pub trait Short {
    /// The JSON number (null for none, or for a NaN or an infinity, which JSON lacks).
    fn short(self) -> Value;
}

impl Short for f32 {
    fn short(self) -> Value {
        // The shortest decimal that reads back as this f32, read as an f64: the same digits.
        self.to_string()
            .parse::<f64>()
            .ok()
            .and_then(serde_json::Number::from_f64)
            .map_or(Value::Null, Value::Number)
    }
}

impl Short for Option<f32> {
    fn short(self) -> Value {
        self.map_or(Value::Null, Short::short)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_f32_reads_as_it_prints() {
        assert_eq!(0.9f32.short().to_string(), "0.9");
        assert_eq!(serde_json::json!(0.9f32).to_string(), "0.8999999761581421");
        assert_eq!(433.92f32.short().to_string(), "433.92");
        assert_eq!(Some(1e-7f32).short().to_string(), "1e-7");
        assert_eq!(f32::NAN.short(), Value::Null);
        assert_eq!(None::<f32>.short(), Value::Null);
    }
}
