//! Names given on a command line, read into the values they name, with an error that
//! lists the names allowed: a controller, a turn mode, a turn order, an agent's test mode.

use shared::control::vocabulary::{ControllerKind, Named, TurnMode, TurnOrder};
use wire::misbehave::Misbehave;

/// A value of a closed set given by its name, or an error listing the names allowed
/// (`"sidewise": one of sequential, parallel, simultaneous`).
pub fn parse_named<T: Named>(s: &str) -> Result<T, String> {
    <T as Named>::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = T::ALL.iter().map(Named::name).collect();
        format!("{s:?}: one of {}", names.join(", "))
    })
}

/// A controller name.
pub fn parse_controller(s: &str) -> Result<ControllerKind, String> {
    parse_named(s)
}

/// A turn mode name.
pub fn parse_turn_mode(s: &str) -> Result<TurnMode, String> {
    parse_named(s)
}

/// A turn order name.
pub fn parse_turn_order(s: &str) -> Result<TurnOrder, String> {
    parse_named(s)
}

/// `AGENT=MODE`, the mode one of [`Misbehave::ALL`] by name.
pub fn parse_misbehave(s: &str) -> Result<(usize, Misbehave), String> {
    let (a, m) = s
        .split_once('=')
        .ok_or_else(|| format!("{s:?}: expected AGENT=MODE, e.g. 3=nan"))?;
    let agent = a
        .parse()
        .map_err(|_| format!("{a:?} is not an agent index"))?;
    let mode = m.parse::<Misbehave>().map_err(|e| e.to_string())?;
    Ok((agent, mode))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wrong_name_lists_the_names_allowed_in_order() {
        assert_eq!(parse_turn_mode("parallel"), Ok(TurnMode::Parallel));
        assert_eq!(
            parse_turn_mode("sidewise"),
            Err("\"sidewise\": one of sequential, parallel, simultaneous".to_string())
        );
        assert_eq!(
            parse_turn_order("last"),
            Err("\"last\": one of agent, front-first".to_string())
        );
        assert!(parse_controller("apf").is_err_and(|e| e.contains("best-point")));
    }
}
