//! What a program answers, read and checked: another process's output is untrusted
//! input, so a line is refused, with the reason, unless it is one well-formed reply with
//! finite numbers and bounded lists.

use serde::{Deserialize, Serialize};

use super::MAX_LINE_BYTES;
use super::messages::{Ready, XY};
use crate::control::vocabulary::MAX_WAYPOINTS;

/// The longest controller name a [`Ready`] may give, in characters.
pub const MAX_NAME_CHARS: usize = 64;

/// A line a program sends the agent.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Reply {
    /// The answer to the hello.
    Ready(Ready),
    /// A move.
    Move(MoveReply),
    /// The agent stays where it stands this turn.
    Stay,
}

/// A move: the polyline the agent follows this turn, from where it stands (its first
/// waypoint may be where it stands, or the first point it goes to).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MoveReply {
    /// The waypoints, metres: at least one, at most
    /// [`MAX_WAYPOINTS`](crate::control::vocabulary::MAX_WAYPOINTS).
    pub waypoints_m: Vec<XY>,
    /// The heading the agent ends with, radians, for a unicycle or a car (required for
    /// them, ignored for a holonomic agent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_heading_rad: Option<f64>,
}

impl Reply {
    /// The reply as one line of JSON, its newline included.
    pub fn to_line(&self) -> String {
        super::json_line(self)
    }
}

/// Why a line from a program is not a reply.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ReplyError {
    /// The line is longer than [`MAX_LINE_BYTES`].
    #[error("a line of {bytes} bytes, over the limit of {MAX_LINE_BYTES}")]
    TooLong {
        /// Its length, bytes.
        bytes: usize,
    },
    /// The line is not one JSON object of a known `type` with the fields that type has.
    #[error("not a reply: {reason}")]
    Malformed {
        /// What the JSON reader found wrong.
        reason: String,
    },
    /// A number is not finite (infinite, or out of range).
    #[error("{field} is not a finite number")]
    NotFinite {
        /// The field.
        field: &'static str,
    },
    /// A move with no waypoint.
    #[error("a move with no waypoint (send {{\"type\": \"stay\"}} to stay)")]
    NoWaypoints,
    /// A move with more waypoints than an agent may publish.
    #[error("a move of {count} waypoints, over the limit of {MAX_WAYPOINTS}")]
    TooManyWaypoints {
        /// How many it had.
        count: usize,
    },
    /// A controller name too long, or with control characters in it.
    #[error("a controller name must be at most {MAX_NAME_CHARS} printable characters")]
    BadName,
}

/// Read one line a program sent (its newline, if there, left out) into a [`Reply`],
/// every number finite and every list within its bound.
///
/// ```
/// use shared::control::protocol::{Reply, ReplyError, read_reply};
///
/// let reply = read_reply(br#"{"type": "move", "waypoints_m": [[1.0, 2.0], [1.5, 2.0]]}"#);
/// assert!(matches!(reply, Ok(Reply::Move(ref m)) if m.waypoints_m.len() == 2));
/// assert_eq!(read_reply(br#"{"type": "stay"}"#), Ok(Reply::Stay));
/// assert!(matches!(read_reply(b"stay"), Err(ReplyError::Malformed { .. })));
/// ```
pub fn read_reply(line: &[u8]) -> Result<Reply, ReplyError> {
    if line.len() > MAX_LINE_BYTES {
        return Err(ReplyError::TooLong { bytes: line.len() });
    }
    let reply: Reply = serde_json::from_slice(line).map_err(|e| ReplyError::Malformed {
        reason: e.to_string(),
    })?;
    check(&reply)?;
    Ok(reply)
}

fn check(reply: &Reply) -> Result<(), ReplyError> {
    match reply {
        Reply::Ready(ready) => {
            if let Some(name) = &ready.name
                && (name.chars().count() > MAX_NAME_CHARS || name.chars().any(char::is_control))
            {
                return Err(ReplyError::BadName);
            }
        }
        Reply::Move(MoveReply {
            waypoints_m,
            end_heading_rad,
        }) => {
            if waypoints_m.is_empty() {
                return Err(ReplyError::NoWaypoints);
            }
            if waypoints_m.len() > MAX_WAYPOINTS {
                return Err(ReplyError::TooManyWaypoints {
                    count: waypoints_m.len(),
                });
            }
            if waypoints_m.iter().flatten().any(|v| !v.is_finite()) {
                return Err(ReplyError::NotFinite {
                    field: "waypoints_m",
                });
            }
            if end_heading_rad.is_some_and(|h| !h.is_finite()) {
                return Err(ReplyError::NotFinite {
                    field: "end_heading_rad",
                });
            }
        }
        Reply::Stay => {}
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line, and whether the error it gets is the one expected.
    type Case<'a> = (&'a [u8], fn(&ReplyError) -> bool);

    #[test]
    fn each_kind_of_bad_line_is_refused_with_its_reason() {
        let too_many = format!(
            r#"{{"type": "move", "waypoints_m": [{}]}}"#,
            vec!["[1, 2]"; MAX_WAYPOINTS + 1].join(",")
        );
        let long_name = format!(
            r#"{{"type": "ready", "protocol": 1, "name": "{}"}}"#,
            "n".repeat(MAX_NAME_CHARS + 1)
        );
        let cases: [Case<'_>; 10] = [
            (b"", |e| matches!(e, ReplyError::Malformed { .. })),
            (b"\xff\xfe", |e| matches!(e, ReplyError::Malformed { .. })),
            (b"[1, 2]", |e| matches!(e, ReplyError::Malformed { .. })),
            (
                br#"{"type": "jump"}"#,
                |e| matches!(e, ReplyError::Malformed { reason } if reason.contains("jump")),
            ),
            (
                br#"{"type": "move"}"#,
                |e| matches!(e, ReplyError::Malformed { reason } if reason.contains("waypoints_m")),
            ),
            (br#"{"type": "move", "waypoints_m": []}"#, |e| {
                matches!(e, ReplyError::NoWaypoints)
            }),
            (br#"{"type": "move", "waypoints_m": [[1e999, 0]]}"#, |e| {
                matches!(
                    e,
                    ReplyError::Malformed { .. } | ReplyError::NotFinite { .. }
                )
            }),
            (
                too_many.as_bytes(),
                |e| matches!(e, ReplyError::TooManyWaypoints { count } if *count == MAX_WAYPOINTS + 1),
            ),
            (long_name.as_bytes(), |e| matches!(e, ReplyError::BadName)),
            (
                br#"{"type": "ready", "protocol": 1, "name": "a\u001b[2J"}"#,
                |e| matches!(e, ReplyError::BadName),
            ),
        ];
        for (line, expected) in cases {
            match read_reply(line) {
                Err(e) => assert!(expected(&e), "{}: {e:?}", String::from_utf8_lossy(line)),
                Ok(reply) => panic!("{} was read as {reply:?}", String::from_utf8_lossy(line)),
            }
        }
    }

    #[test]
    fn a_line_over_the_limit_is_refused_before_it_is_parsed() {
        let line = vec![b' '; MAX_LINE_BYTES + 1];
        assert_eq!(
            read_reply(&line),
            Err(ReplyError::TooLong {
                bytes: MAX_LINE_BYTES + 1
            })
        );
    }

    #[test]
    fn good_replies_are_read_and_unknown_fields_ignored() {
        assert_eq!(
            read_reply(br#"{"type": "ready", "protocol": 1, "name": "apf", "extra": [1]}"#),
            Ok(Reply::Ready(Ready {
                protocol: 1,
                name: Some("apf".into())
            }))
        );
        assert_eq!(
            read_reply(br#"{"type": "move", "waypoints_m": [[1, 2]], "end_heading_rad": 0.5}"#),
            Ok(Reply::Move(MoveReply {
                waypoints_m: vec![[1.0, 2.0]],
                end_heading_rad: Some(0.5)
            }))
        );
    }

    proptest::proptest! {
        #[test]
        fn no_line_makes_the_reader_panic(line in proptest::collection::vec(proptest::num::u8::ANY, 0..200)) {
            let _ = read_reply(&line);
        }

        #[test]
        fn every_reply_read_has_finite_numbers(
            x in proptest::num::f64::ANY, y in proptest::num::f64::ANY, h in proptest::num::f64::ANY,
        ) {
            let line = serde_json::json!({"type": "move", "waypoints_m": [[x, y]], "end_heading_rad": h});
            if let Ok(Reply::Move(MoveReply { waypoints_m, end_heading_rad })) = read_reply(line.to_string().as_bytes()) {
                proptest::prop_assert!(waypoints_m.iter().flatten().all(|v| v.is_finite()));
                proptest::prop_assert!(end_heading_rad.is_none_or(f64::is_finite));
            }
        }
    }
}
