//! Foxglove's well-known schemas in `run.mcap` (JSON-encoded, with JSON schemas), so the
//! log opens in Foxglove as a scene: `foxglove.SceneUpdate` (`/scene`: obstacles,
//! moving obstacles, agents, their slots, best points, moves and sensing circles),
//! `foxglove.PosesInFrame` (`/centre/plan`: the centre path planned, then each replan;
//! `/centre/path`: the path followed so far) and `foxglove.FrameTransform` (`/tf`: the
//! formation frame in the field frame). Everything lies in the plane `z = 0` of the frame
//! `field`.

use serde::Serialize;
use serde_json::{Value, json};
use shared::geometry::{Point, Pose};
use shared::run::record::Step;
use shared::world::scenario::Scenario;

/// The frame every position is in.
pub const FIELD_FRAME: &str = "field";

/// The formation's frame: at the centre, turned by its heading.
pub const FORMATION_FRAME: &str = "formation";

/// Height of the discs drawn for bodies, metres (they are flat in the model).
const DISC_HEIGHT_M: f64 = 0.05;

/// The resolution of the positions of agents, slots, best points, moves and moving
/// obstacles in the scene, metres.
pub const SCENE_RESOLUTION_M: f64 = 1e-4;

/// Foxglove's `LinePrimitive` types (`LINE_STRIP` = 0 is not used).
const LINE_LOOP: u8 = 1;
const LINE_LIST: u8 = 2;

fn number() -> Value {
    json!({"type": "number"})
}

fn integer() -> Value {
    json!({"type": "integer", "minimum": 0})
}

fn string() -> Value {
    json!({"type": "string"})
}

fn object(properties: Value) -> Value {
    let required: Vec<String> = properties
        .as_object()
        .map(|p| p.keys().cloned().collect())
        .unwrap_or_default();
    json!({"type": "object", "properties": properties, "required": required})
}

fn array(items: Value) -> Value {
    json!({"type": "array", "items": items})
}

fn time() -> Value {
    object(json!({"sec": integer(), "nsec": integer()}))
}

fn vector3() -> Value {
    object(json!({"x": number(), "y": number(), "z": number()}))
}

fn quaternion() -> Value {
    object(json!({"x": number(), "y": number(), "z": number(), "w": number()}))
}

fn color() -> Value {
    object(json!({"r": number(), "g": number(), "b": number(), "a": number()}))
}

fn pose_schema() -> Value {
    object(json!({"position": vector3(), "orientation": quaternion()}))
}

/// The JSON schema of `foxglove.SceneUpdate`, as far as this log uses it (entities of
/// cylinders and line strips; every other primitive list present and empty).
pub fn scene_update_schema() -> Value {
    let cylinder = object(json!({
        "pose": pose_schema(), "size": vector3(), "bottom_scale": number(),
        "top_scale": number(), "color": color()
    }));
    let line = object(json!({
        "type": integer(), "pose": pose_schema(), "thickness": number(),
        "scale_invariant": {"type": "boolean"}, "points": array(vector3()),
        "color": color(), "colors": array(color()), "indices": array(integer())
    }));
    let entity = object(json!({
        "timestamp": time(), "frame_id": string(), "id": string(), "lifetime": time(),
        "frame_locked": {"type": "boolean"}, "metadata": array(object(json!({"key": string(), "value": string()}))),
        "arrows": array(json!({})), "cubes": array(json!({})), "spheres": array(json!({})),
        "cylinders": array(cylinder), "lines": array(line), "triangles": array(json!({})),
        "texts": array(json!({})), "models": array(json!({}))
    }));
    let deletion = object(json!({"timestamp": time(), "type": integer(), "id": string()}));
    let mut schema = object(json!({"deletions": array(deletion), "entities": array(entity)}));
    schema["title"] = json!("foxglove.SceneUpdate");
    schema
}

/// The JSON schema of `foxglove.PosesInFrame`.
pub fn poses_in_frame_schema() -> Value {
    let mut schema = object(json!({
        "timestamp": time(), "frame_id": string(), "poses": array(pose_schema())
    }));
    schema["title"] = json!("foxglove.PosesInFrame");
    schema
}

/// The JSON schema of `foxglove.FrameTransform`.
pub fn frame_transform_schema() -> Value {
    let mut schema = object(json!({
        "timestamp": time(), "parent_frame_id": string(), "child_frame_id": string(),
        "translation": vector3(), "rotation": quaternion()
    }));
    schema["title"] = json!("foxglove.FrameTransform");
    schema
}

/// Foxglove's `Time`.
#[derive(Clone, Copy, Serialize)]
struct Time {
    sec: u64,
    nsec: u64,
}

/// A log time in nanoseconds as Foxglove's `{sec, nsec}`.
fn stamp(log_time_ns: u64) -> Time {
    Time {
        sec: log_time_ns / 1_000_000_000,
        nsec: log_time_ns % 1_000_000_000,
    }
}

#[derive(Clone, Copy, Serialize)]
struct Vector3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Clone, Copy, Serialize)]
struct Quaternion {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Clone, Copy, Serialize)]
struct FoxPose {
    position: Vector3,
    orientation: Quaternion,
}

#[derive(Clone, Copy, Serialize)]
struct Color {
    r: f64,
    g: f64,
    b: f64,
    a: f64,
}

#[derive(Serialize)]
struct Cylinder {
    pose: FoxPose,
    size: Vector3,
    bottom_scale: f64,
    top_scale: f64,
    color: Color,
}

#[derive(Serialize)]
struct LineStrip {
    #[serde(rename = "type")]
    kind: u8,
    pose: FoxPose,
    thickness: f64,
    scale_invariant: bool,
    points: Vec<Vector3>,
    color: Color,
    colors: [Color; 0],
    indices: [u32; 0],
}

/// An empty list of a primitive this log does not use.
type None0 = [(); 0];

#[derive(Serialize)]
struct Entity {
    timestamp: Time,
    frame_id: &'static str,
    id: &'static str,
    lifetime: Time,
    frame_locked: bool,
    metadata: None0,
    arrows: None0,
    cubes: None0,
    spheres: None0,
    cylinders: Vec<Cylinder>,
    lines: Vec<LineStrip>,
    triangles: None0,
    texts: None0,
    models: None0,
}

/// `foxglove.SceneUpdate`.
#[derive(Serialize)]
pub struct SceneUpdate {
    deletions: None0,
    entities: Vec<Entity>,
}

/// `foxglove.PosesInFrame`.
#[derive(Serialize)]
pub struct PosesInFrame {
    timestamp: Time,
    frame_id: &'static str,
    poses: Vec<FoxPose>,
}

/// `foxglove.FrameTransform`.
#[derive(Serialize)]
pub struct FrameTransform {
    timestamp: Time,
    parent_frame_id: &'static str,
    child_frame_id: &'static str,
    translation: Vector3,
    rotation: Quaternion,
}

/// The rotation by `heading_rad` about `z`.
fn rotation(heading_rad: f64) -> Quaternion {
    let half = heading_rad / 2.0;
    Quaternion {
        x: 0.0,
        y: 0.0,
        z: half.sin(),
        w: half.cos(),
    }
}

fn flat(p: &Point) -> Vector3 {
    Vector3 {
        x: p.x,
        y: p.y,
        z: 0.0,
    }
}

/// What the scene draws of a position that changes every step: rounded to
/// [`SCENE_RESOLUTION_M`], far below what a viewer can tell apart, so that its JSON is a
/// few digits rather than seventeen. The exact positions are on `/formation/step`.
fn shown(p: &Point) -> Point {
    let round = |v: f64| (v / SCENE_RESOLUTION_M).round() * SCENE_RESOLUTION_M;
    Point::new(round(p.x), round(p.y))
}

fn pose_at(p: &Point, heading_rad: f64) -> FoxPose {
    FoxPose {
        position: flat(p),
        orientation: rotation(heading_rad),
    }
}

fn rgba(r: f64, g: f64, b: f64, a: f64) -> Color {
    Color { r, g, b, a }
}

fn disc(centre: &Point, radius_m: f64, color: Color) -> Cylinder {
    let d = 2.0 * radius_m;
    Cylinder {
        pose: pose_at(centre, 0.0),
        size: Vector3 {
            x: d,
            y: d,
            z: DISC_HEIGHT_M,
        },
        bottom_scale: 1.0,
        top_scale: 1.0,
        color,
    }
}

/// A line primitive of Foxglove's type `kind` through `points`.
fn lines_of(kind: u8, points: &[Point], thickness_m: f64, color: Color) -> LineStrip {
    LineStrip {
        kind,
        pose: pose_at(&Point::origin(), 0.0),
        thickness: thickness_m,
        scale_invariant: false,
        points: points.iter().map(flat).collect(),
        color,
        colors: [],
        indices: [],
    }
}

/// One `LINE_LIST` through `points` (pairs, each a segment), or none when there are none.
fn line_list(points: &[Point], thickness_m: f64, color: Color) -> Vec<LineStrip> {
    match points.is_empty() {
        true => vec![],
        false => vec![lines_of(LINE_LIST, points, thickness_m, color)],
    }
}

fn entity(
    id: &'static str,
    log_time_ns: u64,
    cylinders: Vec<Cylinder>,
    lines: Vec<LineStrip>,
) -> Entity {
    Entity {
        timestamp: stamp(log_time_ns),
        frame_id: FIELD_FRAME,
        id,
        lifetime: Time { sec: 0, nsec: 0 },
        frame_locked: false,
        metadata: [],
        arrows: [],
        cubes: [],
        spheres: [],
        cylinders,
        lines,
        triangles: [],
        texts: [],
        models: [],
    }
}

/// Each agent's slot in the formation frame, as the scene draws it: the slot of `step`
/// turned back about the centre by the centre's heading, rounded to
/// [`SCENE_RESOLUTION_M`]. The same from step to step unless the slots change.
pub fn slots_in_formation(step: &Step) -> Vec<Point> {
    let centre = step.centre.position();
    let (sin, cos) = step.centre.heading_rad.sin_cos();
    step.agents
        .iter()
        .map(|a| {
            let d = a.slot - centre;
            shown(&Point::new(cos * d.x + sin * d.y, -sin * d.x + cos * d.y))
        })
        .collect()
}

/// The scene at the end of `step`: each entity replaces the one of the same id before it.
/// `known_unknown[i]`: whether unknown obstacle `i` is known by now (drawn only then);
/// `with_obstacles`: whether to send the static obstacles (at step 0 and when one is
/// found: they persist in between); `slots`: the slots in the formation frame
/// ([`slots_in_formation`]), to send when they are not those sent before (they move
/// with the frame `formation`, locked to it, and persist in between).
pub fn scene_update(
    scenario: &Scenario,
    step: &Step,
    known_unknown: &[bool],
    with_obstacles: bool,
    slots: Option<&[Point]>,
    log_time_ns: u64,
) -> SceneUpdate {
    let grey = || rgba(0.45, 0.45, 0.45, 1.0);
    let mut entities = Vec::with_capacity(7);
    if with_obstacles {
        let mut obstacles: Vec<Cylinder> = scenario
            .obstacles
            .iter()
            .map(|o| disc(&o.centre, o.radius_m, grey()))
            .collect();
        obstacles.extend(
            scenario
                .unknown
                .iter()
                .zip(known_unknown)
                .filter(|(_, known)| **known)
                .map(|(o, _)| disc(&o.centre, o.radius_m, rgba(0.6, 0.35, 0.2, 1.0))),
        );
        let polygons = scenario
            .polygons
            .iter()
            .map(|p| lines_of(LINE_LOOP, p.vertices(), 0.05, grey()))
            .collect();
        entities.push(entity("obstacles", log_time_ns, obstacles, polygons));
    }
    let moving = scenario
        .moving
        .iter()
        .zip(&step.moving)
        .map(|(m, at)| disc(&shown(at), m.radius_m, rgba(0.8, 0.5, 0.1, 1.0)))
        .collect();
    let agents = scenario
        .agents
        .iter()
        .zip(&step.agents)
        .map(|(spec, a)| {
            let color = if a.alive {
                rgba(0.12, 0.47, 0.71, 1.0)
            } else {
                rgba(0.2, 0.2, 0.2, 1.0)
            };
            disc(&shown(&a.position), spec.radius_m, color)
        })
        .collect();
    if let Some(slots) = slots {
        let discs = slots
            .iter()
            .map(|at| disc(at, 0.05, rgba(0.2, 0.63, 0.17, 0.8)))
            .collect();
        entities.push(Entity {
            frame_id: FORMATION_FRAME,
            frame_locked: true,
            ..entity("slots", log_time_ns, discs, vec![])
        });
    }
    // A best point drawn on its slot would hide under it: only the others are drawn.
    let best = step
        .agents
        .iter()
        .filter(|a| shown(&a.best) != shown(&a.slot))
        .map(|a| disc(&shown(&a.best), 0.04, rgba(0.89, 0.1, 0.11, 0.8)))
        .collect();
    let sensing = scenario
        .agents
        .iter()
        .zip(&step.agents)
        .filter_map(|(spec, a)| {
            spec.sensing_radius_m
                .map(|r| disc(&shown(&a.position), r, rgba(0.12, 0.47, 0.71, 0.08)))
        })
        .collect();
    // Every move's segments in one line list: one primitive, not one per agent.
    let segments: Vec<Point> = step
        .agents
        .iter()
        .flat_map(|a| a.waypoints.windows(2))
        .flat_map(|pair| [shown(&pair[0]), shown(&pair[1])])
        .collect();
    let moves = line_list(&segments, 0.03, rgba(0.12, 0.47, 0.71, 0.9));
    // The way each agent with a heading faces: a segment from its centre to its rim.
    let headings: Vec<Point> = scenario
        .agents
        .iter()
        .zip(&step.agents)
        .filter_map(|(spec, a)| {
            let heading_rad = a.heading_rad?;
            let (sin, cos) = heading_rad.sin_cos();
            let tip = a.position + spec.radius_m * shared::geometry::Vector::new(cos, sin);
            Some([shown(&a.position), shown(&tip)])
        })
        .flatten()
        .collect();
    let headings = line_list(&headings, 0.04, rgba(0.95, 0.95, 0.95, 1.0));
    entities.extend([
        entity("moving", log_time_ns, moving, vec![]),
        entity("agents", log_time_ns, agents, headings),
        entity("best_points", log_time_ns, best, vec![]),
        entity("sensing", log_time_ns, sensing, vec![]),
        entity("moves", log_time_ns, vec![], moves),
    ]);
    SceneUpdate {
        deletions: [],
        entities,
    }
}

/// Poses in the field frame at `log_time_ns`.
pub fn poses_in_frame(poses: &[Pose], log_time_ns: u64) -> PosesInFrame {
    PosesInFrame {
        timestamp: stamp(log_time_ns),
        frame_id: FIELD_FRAME,
        poses: poses
            .iter()
            .map(|p| pose_at(&Point::new(p.x_m, p.y_m), p.heading_rad))
            .collect(),
    }
}

/// The formation frame at the centre `centre`.
pub fn frame_transform(centre: &Pose, log_time_ns: u64) -> FrameTransform {
    FrameTransform {
        timestamp: stamp(log_time_ns),
        parent_frame_id: FIELD_FRAME,
        child_frame_id: FORMATION_FRAME,
        translation: Vector3 {
            x: centre.x_m,
            y: centre.y_m,
            z: 0.0,
        },
        rotation: rotation(centre.heading_rad),
    }
}

/// Writes `value` as `serde_json` does.
fn put(out: &mut Vec<u8>, value: &impl Serialize) {
    // Writing into a Vec cannot fail, and these values always serialise.
    let _ = serde_json::to_writer(&mut *out, value);
}

/// The JSON of the last value written of a kind, kept while the next is the same: most
/// discs of an entity share their size, colour and orientation.
#[derive(Default)]
struct Repeated {
    bits: Vec<u64>,
    json: Vec<u8>,
}

impl Repeated {
    fn put(&mut self, out: &mut Vec<u8>, bits: &[u64], value: &impl Serialize) {
        if self.bits != bits {
            self.bits = bits.to_vec();
            self.json.clear();
            put(&mut self.json, value);
        }
        out.extend_from_slice(&self.json);
    }
}

impl SceneUpdate {
    /// Append this message's JSON to `out`: the same value `serde_json` writes (checked by
    /// a test), with the discs written from a template, their repeated sizes, colours and
    /// orientations formatted once. The scene is most of the log, and most of it discs.
    pub fn write_json(&self, out: &mut Vec<u8>) {
        let discs: usize = self.entities.iter().map(|e| e.cylinders.len()).sum();
        out.reserve(512 + 260 * discs);
        out.extend_from_slice(br#"{"deletions":[],"entities":["#);
        let (mut size, mut color, mut orientation) = Default::default();
        for (i, e) in self.entities.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            out.extend_from_slice(br#"{"timestamp":"#);
            put(out, &e.timestamp);
            out.extend_from_slice(br#","frame_id":"#);
            put(out, &e.frame_id);
            out.extend_from_slice(br#","id":"#);
            put(out, &e.id);
            out.extend_from_slice(br#","lifetime":"#);
            put(out, &e.lifetime);
            out.extend_from_slice(match e.frame_locked {
                true => br#","frame_locked":true,"#,
                false => br#","frame_locked":false,"#,
            });
            out.extend_from_slice(
                br#""metadata":[],"arrows":[],"cubes":[],"spheres":[],"cylinders":["#,
            );
            for (k, c) in e.cylinders.iter().enumerate() {
                if k > 0 {
                    out.push(b',');
                }
                let p = &c.pose;
                out.extend_from_slice(br#"{"pose":{"position":"#);
                put(out, &p.position);
                out.extend_from_slice(br#","orientation":"#);
                let o = &p.orientation;
                let o_bits = [o.x, o.y, o.z, o.w].map(f64::to_bits);
                Repeated::put(&mut orientation, out, &o_bits, o);
                out.extend_from_slice(br#"},"size":"#);
                let s_bits = [c.size.x, c.size.y, c.size.z].map(f64::to_bits);
                Repeated::put(&mut size, out, &s_bits, &c.size);
                out.extend_from_slice(br#","bottom_scale":"#);
                put(out, &c.bottom_scale);
                out.extend_from_slice(br#","top_scale":"#);
                put(out, &c.top_scale);
                out.extend_from_slice(br#","color":"#);
                let c_bits = [c.color.r, c.color.g, c.color.b, c.color.a].map(f64::to_bits);
                Repeated::put(&mut color, out, &c_bits, &c.color);
                out.push(b'}');
            }
            out.extend_from_slice(br#"],"lines":"#);
            put(out, &e.lines);
            out.extend_from_slice(br#","triangles":[],"texts":[],"models":[]}"#);
        }
        out.extend_from_slice(b"]}");
    }
}

#[cfg(test)]
mod tests;
