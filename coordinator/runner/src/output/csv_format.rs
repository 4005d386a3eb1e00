//! How the CSV files of a run folder are written (`docs/outputs.md`): the number format
//! of their cells, the header of a row type, and a whole file's bytes.
//!
//! Numbers are written as Rust's `Display` gives them (`0.0000001`, `-0`, `NaN`, `inf`:
//! the shortest digits that read back to the same bits, never an exponent), not as the
//! csv crate's own float form; `alive` as `1` or `0`.

use serde::Serialize;
use serde::de::{self, DeserializeOwned, Deserializer, Visitor};

/// An `f64` column: written with `Display`, read with `str::parse` (the csv reader's).
pub(super) mod display_f64 {
    use serde::{Deserialize, Deserializer, Serializer};

    pub(in crate::output) fn serialize<S: Serializer>(
        v: &f64,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        serializer.collect_str(v)
    }

    pub(in crate::output) fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<f64, D::Error> {
        f64::deserialize(deserializer)
    }
}

/// A column that a file may lack (outer `None`: not written) and whose cells may be empty
/// (inner `None`); numbers as [`display_f64`] writes them.
pub(super) mod cell_f64 {
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub(in crate::output) fn serialize<S: Serializer>(
        v: &Option<Option<f64>>,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        match v {
            Some(Some(x)) => serializer.collect_str(x),
            _ => serializer.serialize_none(),
        }
    }

    pub(in crate::output) fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Option<Option<f64>>, D::Error> {
        let cell = String::deserialize(deserializer)?;
        if cell.is_empty() {
            return Ok(Some(None));
        }
        cell.parse()
            .map(|v| Some(Some(v)))
            .map_err(|_| D::Error::custom(format!("{cell:?} is not a number")))
    }
}

/// A `bool` column written `1` or `0`; any number but 0 reads as true.
pub(super) mod zero_one {
    use serde::{Deserialize, Deserializer, Serializer};

    pub(in crate::output) fn serialize<S: Serializer>(
        v: &bool,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        serializer.serialize_u8(u8::from(*v))
    }

    pub(in crate::output) fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<bool, D::Error> {
        Ok(u8::deserialize(deserializer)? != 0)
    }
}

/// The column names of row type `R`, in order: the field names its `Deserialize` asks
/// the reader for, which are the names its `Serialize` writes.
pub fn header<R: DeserializeOwned>() -> &'static [&'static str] {
    /// A deserializer that only notes the fields of the struct asked of it.
    struct Probe<'a>(&'a mut &'static [&'static str]);

    impl<'de> Deserializer<'de> for Probe<'_> {
        type Error = de::value::Error;

        fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Self::Error> {
            Err(de::Error::custom("a row is a struct"))
        }

        fn deserialize_struct<V: Visitor<'de>>(
            self,
            _name: &'static str,
            fields: &'static [&'static str],
            _: V,
        ) -> Result<V::Value, Self::Error> {
            *self.0 = fields;
            Err(de::Error::custom("fields noted"))
        }

        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes
            byte_buf option unit unit_struct newtype_struct seq tuple tuple_struct map enum
            identifier ignored_any
        }
    }

    let mut fields: &'static [&'static str] = &[];
    // The probe always ends the deserialisation with an error, after noting the fields.
    let _ = R::deserialize(Probe(&mut fields));
    fields
}

/// A whole CSV file: the header of `R`, then `rows` (the header alone when there are
/// none).
pub fn csv_bytes<R: Serialize + DeserializeOwned>(
    rows: impl IntoIterator<Item = R>,
) -> anyhow::Result<Vec<u8>> {
    csv_bytes_with_columns(rows, header::<R>().len())
}

/// [`csv_bytes`] with only the first `columns` columns of `R` in the header: the rows
/// leave out the optional columns after them (`skip_serializing_if`), as
/// `TrajectoryRow`'s heading columns in a holonomic run.
pub fn csv_bytes_with_columns<R: Serialize + DeserializeOwned>(
    rows: impl IntoIterator<Item = R>,
    columns: usize,
) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    let header = header::<R>();
    w.write_record(&header[..columns.min(header.len())])?;
    for row in rows {
        w.serialize(row)?;
    }
    Ok(w.into_inner()?)
}
