//! Names given on a command line, read into the values they name, with an error that
//! lists the names allowed: a controller, a turn mode, a turn order, an agent's test mode.

use shared::control::vocabulary::{ControllerKind, TurnMode, TurnOrder};
use wire::misbehave::Misbehave;

/// A controller name.
pub fn parse_controller(s: &str) -> Result<ControllerKind, String> {
    ControllerKind::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = ControllerKind::ALL
            .iter()
            .map(ControllerKind::name)
            .collect();
        format!("{s:?}: one of {}", names.join(", "))
    })
}

/// A turn mode name.
pub fn parse_turn_mode(s: &str) -> Result<TurnMode, String> {
    TurnMode::from_name(s)
        .ok_or_else(|| format!("{s:?}: one of sequential, parallel, simultaneous"))
}

/// A turn order name.
pub fn parse_turn_order(s: &str) -> Result<TurnOrder, String> {
    TurnOrder::from_name(s).ok_or_else(|| format!("{s:?}: one of agent, front-first"))
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
