//! A JSON-schema check of the subset the project's schemas use: `type` (`object`,
//! `array`, `number`, `integer`, `string`, `boolean`, `null`, or a list of them),
//! `properties`, `required`, `additionalProperties: false`, `items`, `minItems`,
//! `maxItems`, `enum` and `minimum`; `{}` allows anything. Enough to tell that a message
//! fits its schema.

use serde_json::Value;

/// Check `value` against `schema`; the error names the path of the first mismatch.
pub fn check(schema: &Value, value: &Value) -> Result<(), String> {
    check_at(schema, value, "$")
}

fn check_at(schema: &Value, value: &Value, at: &str) -> Result<(), String> {
    let Some(schema) = schema.as_object() else {
        return Err(format!("{at}: the schema is not an object"));
    };
    let kinds: Vec<&str> = match schema.get("type") {
        Some(Value::String(kind)) => vec![kind.as_str()],
        Some(Value::Array(kinds)) => kinds.iter().filter_map(Value::as_str).collect(),
        _ => Vec::new(),
    };
    if !kinds.is_empty() {
        let mut fits = false;
        for kind in &kinds {
            fits |= match *kind {
                "object" => value.is_object(),
                "array" => value.is_array(),
                "number" => value.is_number(),
                "integer" => value.is_u64() || value.is_i64(),
                "string" => value.is_string(),
                "boolean" => value.is_boolean(),
                "null" => value.is_null(),
                other => return Err(format!("{at}: unknown type {other} in the schema")),
            };
        }
        if !fits {
            return Err(format!(
                "{at}: {value} is not of type {}",
                kinds.join(" or ")
            ));
        }
    }
    if let Some(allowed) = schema.get("enum").and_then(Value::as_array)
        && !allowed.contains(value)
    {
        return Err(format!("{at}: {value} is not one of {allowed:?}"));
    }
    if let Some(array) = value.as_array() {
        if let Some(least) = schema.get("minItems").and_then(Value::as_u64)
            && (array.len() as u64) < least
        {
            return Err(format!("{at}: fewer than {least} items"));
        }
        if let Some(most) = schema.get("maxItems").and_then(Value::as_u64)
            && (array.len() as u64) > most
        {
            return Err(format!("{at}: more than {most} items"));
        }
    }
    if let (Some(minimum), Some(number)) = (
        schema.get("minimum").and_then(Value::as_f64),
        value.as_f64(),
    ) && number < minimum
    {
        return Err(format!("{at}: {number} is below {minimum}"));
    }
    if let Some(object) = value.as_object() {
        for key in schema
            .get("required")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(Value::as_str)
        {
            if !object.contains_key(key) {
                return Err(format!("{at}: `{key}` is missing"));
            }
        }
        if let Some(properties) = schema.get("properties").and_then(Value::as_object) {
            for (key, sub) in properties {
                if let Some(v) = object.get(key) {
                    check_at(sub, v, &format!("{at}.{key}"))?;
                }
            }
            if schema.get("additionalProperties") == Some(&Value::Bool(false))
                && let Some(extra) = object.keys().find(|k| !properties.contains_key(*k))
            {
                return Err(format!("{at}: `{extra}` is no property of the schema"));
            }
        }
    }
    if let (Some(items), Some(array)) = (schema.get("items"), value.as_array()) {
        for (i, v) in array.iter().enumerate() {
            check_at(items, v, &format!("{at}[{i}]"))?;
        }
    }
    Ok(())
}
