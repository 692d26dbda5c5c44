//! Fixed-length arrays read from config files (TOML) with their exact length: serde's `[f64; L]`
//! reads the first `L` elements of a longer array and drops the rest without a word, so
//! `shear = [0.5, 0.5, 7]` would pass as `[0.5, 0.5]`.

use serde::de::{Deserialize, Deserializer, Error as _};

/// For `#[serde(deserialize_with = "crate::exact_array::exactly")]` on a `[f64; L]` field: reads
/// an array of exactly `L` numbers and refuses any other length, naming the length it wants.
pub fn exactly<'de, D, const L: usize>(deserializer: D) -> Result<[f64; L], D::Error>
where
    D: Deserializer<'de>,
{
    let values = Vec::<f64>::deserialize(deserializer)?;
    let len = values.len();
    values
        .try_into()
        .map_err(|_| D::Error::invalid_length(len, &format!("an array of {L} numbers").as_str()))
}

#[cfg(test)]
mod tests {
    #[derive(Debug, serde::Deserialize)]
    struct Pair {
        #[serde(deserialize_with = "super::exactly")]
        pair: [f64; 2],
    }

    #[test]
    fn only_the_exact_length_is_read() {
        let ok: Pair = toml::from_str("pair = [0.5, 1]").unwrap();
        assert_eq!(ok.pair, [0.5, 1.0]);
        for bad in ["pair = [0.5, 0.5, 7]", "pair = [0.5]", "pair = []"] {
            let e = toml::from_str::<Pair>(bad).unwrap_err().to_string();
            assert!(e.contains("an array of 2 numbers"), "{bad}: {e}");
        }
        assert!(toml::from_str::<Pair>("pair = [0.5, \"junk\"]").is_err());
    }
}
