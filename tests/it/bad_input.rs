//! The malformed-input corpus (`tests/bad_scenarios/`; the rules are in
//! `docs/scenario-format.md` and `docs/outputs.md`).
//!
//! Every file there is one malformed scenario whose first line, `# expect: FIELD`, names
//! the field the error must name. Each is refused
//! - by the library: `Scenario::load` (and `load_and_plan`, which also plans the centre
//!   path) returns an error whose `field()` is FIELD and which displays as the one line
//!   `FILE: FIELD: REASON`;
//! - by the real `coordinator validate FILE` and `coordinator run FILE --out DIR` processes:
//!   exit code 2, exactly one line on stderr naming the file and FIELD, nothing on stdout,
//!   and `run` creates nothing (neither DIR nor a default `runs/` folder).
//!
//! Cases too large to commit (more agents or obstacles than the wire holds) are generated
//! here, as are a missing file and a directory. Every process runs under a time limit, so a
//! hang on bad input fails with the file's name instead of stalling the suite.

use crate::support;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use runner::loaded::load_and_plan;
use shared::control::vocabulary::{MAX_AGENTS, MAX_OBSTACLES};
use shared::world::scenario::{Scenario, ScenarioError};

/// The corpus must hold at least this many files.
const MIN_CORPUS_FILES: usize = 30;

/// One malformed scenario and the field its error must name.
pub(crate) struct Case {
    /// The file.
    pub(crate) path: PathBuf,
    /// The field its error must name.
    pub(crate) expect: String,
}

impl Case {
    fn name(&self) -> String {
        self.path.display().to_string()
    }
}

fn corpus_dir() -> PathBuf {
    support::repo_root().join("tests").join("bad_scenarios")
}

/// Every `.toml` file of the corpus, sorted, with its `# expect:` field.
fn corpus() -> Vec<Case> {
    let dir = corpus_dir();
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot read the corpus folder {}: {e}", dir.display()))
        .map(|entry| entry.expect("corpus folder entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    paths
        .into_iter()
        .map(|path| {
            // Bytes, not text: one case is deliberately not UTF-8 after its first line.
            let bytes = std::fs::read(&path)
                .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
            let first = bytes.split(|b| *b == b'\n').next().unwrap_or_default();
            let first = String::from_utf8_lossy(first);
            let expect = first
                .strip_prefix("# expect: ")
                .map(str::trim)
                .filter(|f| !f.is_empty())
                .unwrap_or_else(|| {
                    panic!(
                        "{}: the first line must be `# expect: FIELD`, found {first:?}",
                        path.display()
                    )
                })
                .to_string();
            Case { path, expect }
        })
        .collect()
}

/// Problems with a refusal by a `coordinator` process (empty when it is right): exit code
/// 2, nothing on stdout, one line on stderr (an empty trailing newline aside) that names
/// the file and the expected field as `FILE: FIELD: REASON`.
pub(crate) fn refusal_problems(command: &str, case: &Case, output: &Output) -> Vec<String> {
    let mut problems = Vec::new();
    let stderr = String::from_utf8_lossy(&output.stderr);
    let stdout = String::from_utf8_lossy(&output.stdout);
    if output.status.code() != Some(2) {
        problems.push(format!(
            "exit status {} instead of exit code 2 (stderr: {stderr:?})",
            output.status
        ));
    }
    if !stdout.is_empty() {
        problems.push(format!("wrote to stdout: {stdout:?}"));
    }
    let body = stderr.strip_suffix('\n').unwrap_or(&stderr);
    let lines: Vec<&str> = body.split('\n').collect();
    if body.is_empty() || lines.len() != 1 {
        problems.push(format!(
            "stderr is {} lines, not exactly one: {stderr:?}",
            if body.is_empty() { 0 } else { lines.len() }
        ));
    } else {
        let line = lines[0];
        let file_and_field = format!("{}: {}: ", case.name(), case.expect);
        match line.find(&file_and_field) {
            None => problems.push(format!(
                "stderr line does not name `{file_and_field}` (the file and the expected field): {line:?}"
            )),
            Some(at) if line[at + file_and_field.len()..].trim().is_empty() => {
                problems.push(format!("stderr line gives no reason: {line:?}"));
            }
            Some(_) => {}
        }
    }
    problems
        .into_iter()
        .map(|p| format!("coordinator {command} {}: {p}", case.name()))
        .collect()
}

/// Problems with the error `got` for `case` from `what` (empty when it is right): it names
/// the expected field and displays as the one line `FILE: FIELD: REASON`.
fn error_problems(what: &str, case: &Case, got: &ScenarioError) -> Option<String> {
    let line = got.to_string();
    let prefix = format!("{}: {}: ", case.name(), case.expect);
    if got.field() != case.expect {
        Some(format!(
            "{what}: field() is {:?}, expected {:?} (error: {line})",
            got.field(),
            case.expect
        ))
    } else if line.contains('\n') || line.contains('\r') {
        Some(format!("{what}: the error is not one line: {line:?}"))
    } else if !line.starts_with(&prefix) || line.len() == prefix.len() {
        Some(format!(
            "{what}: the error does not read `{prefix}REASON`: {line:?}"
        ))
    } else {
        None
    }
}

/// Problems with the library's refusal of `case` (empty when it is right).
///
/// `Scenario::load` must refuse it naming the expected field, except a scenario whose
/// only fault is that the centre has no path (`path`): checking that takes the planner,
/// so `load` may accept it. Then `load_and_plan`, which the `coordinator` commands call,
/// must refuse every case naming the expected field. Panics are caught and reported.
fn library_problems(case: &Case) -> Vec<String> {
    let path = case.path.clone();
    let loaded = std::panic::catch_unwind(move || Scenario::load(&path));
    let mut problems = Vec::new();
    match loaded {
        Err(_) => problems.push("Scenario::load panicked".to_string()),
        Ok(Ok(_)) if case.expect == "path" => {}
        Ok(Ok(s)) => problems.push(format!(
            "Scenario::load accepted it ({} agents, {} obstacles)",
            s.agents.len(),
            s.obstacles.len()
        )),
        Ok(Err(e)) => problems.extend(error_problems("Scenario::load", case, &e)),
    }
    let path = case.path.clone();
    match std::panic::catch_unwind(move || load_and_plan(Some(&path))) {
        Err(_) => problems.push("load_and_plan panicked".to_string()),
        Ok(Ok(loaded)) => problems.push(format!(
            "load_and_plan accepted it (centre path of {} poses)",
            loaded.centre_path.len()
        )),
        Ok(Err(e)) => problems.extend(error_problems("load_and_plan", case, &e)),
    }
    problems
        .into_iter()
        .map(|p| format!("library {}: {p}", case.name()))
        .collect()
}

/// Problems with `coordinator validate` refusing `case`.
fn validate_problems(case: &Case) -> Vec<String> {
    let mut cmd = Command::new(support::coordinator_bin());
    cmd.arg("validate").arg(&case.path);
    match support::run_bounded(cmd) {
        Ok(output) => refusal_problems("validate", case, &output),
        Err(e) => vec![format!("coordinator validate {}: {e}", case.name())],
    }
}

/// Problems with `coordinator run --out` refusing `case`: as for `validate`, and neither
/// the output folder nor anything else appears in the (otherwise empty) working folder.
fn run_problems(case: &Case) -> Vec<String> {
    command_problems("run", case)
}

/// What is wrong with how `coordinator COMMAND` refused `case`: the exit code and line as
/// for `validate`, and nothing created, neither the `--out` folder nor anything else in
/// the working folder.
fn command_problems(command: &str, case: &Case) -> Vec<String> {
    let work = tempfile::tempdir().expect("temporary working folder");
    let out = work.path().join("out");
    let mut cmd = Command::new(support::coordinator_bin());
    cmd.current_dir(work.path())
        .arg(command)
        .arg(&case.path)
        .arg("--out")
        .arg(&out);
    if command == "run" {
        // `run` draws a progress bar; `compare` has none to hush.
        cmd.arg("--quiet");
    }
    let mut problems = match support::run_bounded(cmd) {
        Ok(output) => refusal_problems(command, case, &output),
        Err(e) => vec![e],
    };
    if out.exists() {
        problems.push(format!(
            "coordinator {command} {}: created the --out folder {}",
            case.name(),
            out.display()
        ));
    }
    let left: Vec<String> = std::fs::read_dir(work.path())
        .expect("read the working folder")
        .map(|e| {
            e.expect("working folder entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    if !left.is_empty() {
        problems.push(format!(
            "coordinator {command} {}: left {left:?} in its working folder",
            case.name()
        ));
    }
    problems
}

/// Fail with every problem listed, one per line.
fn assert_no_problems(what: &str, checked: usize, problems: &[String]) {
    assert!(
        problems.is_empty(),
        "{what}: {} problem(s) over {checked} case(s):\n{}",
        problems.len(),
        problems.join("\n")
    );
}

/// A small valid scenario: the cases generated below change one thing in it.
fn valid_scenario(slots: &str, obstacles: &str) -> String {
    format!(
        r#"name = "generated"
seed = 1

[field]
width_m = 200.0
height_m = 200.0

[obstacles]
radius_m = 0.1
{obstacles}

[formation]
agent_radius_m = 0.3
slots = [
{slots}]

[path]
start = {{ x_m = 20.0, y_m = 20.0, heading_deg = 0.0 }}
goal = {{ x_m = 198.0, y_m = 198.0, heading_deg = 0.0 }}
turning_radius_m = 2.0
step_m = 0.5
centre_clearance_m = 0.3
"#
    )
}

/// `n` slots on a square grid 0.7 m apart around the centre (agents of 0.3 m: Assumption
/// 2 holds), all inside the field at the start pose.
fn grid_slots(n: usize) -> String {
    let side = (n as f64).sqrt().ceil() as usize;
    let mut text = String::new();
    for k in 0..n {
        let x = 0.7 * ((k % side) as f64 - 0.5 * (side - 1) as f64);
        let y = 0.7 * ((k / side) as f64 - 0.5 * (side - 1) as f64);
        let _ = writeln!(
            text,
            "  {{ r_m = {:?}, theta_deg = {:?} }},",
            x.hypot(y),
            y.atan2(x).to_degrees()
        );
    }
    text
}

/// `n` (at most 128 x 129) explicit obstacles on a grid 1 m apart from (30, 30), inside
/// the field and clear of the start and the goal; as `positions_m` or as
/// `[[obstacles.disk]]` tables.
fn grid_obstacles(n: usize, as_disks: bool) -> String {
    assert!(n <= 128 * 129, "the grid holds 128 x 129 obstacles");
    let xy = |k: usize| (30.0 + (k % 128) as f64, 30.0 + (k / 128) as f64);
    let mut text = String::new();
    if as_disks {
        for k in 0..n {
            let (x, y) = xy(k);
            let _ = write!(text, "\n[[obstacles.disk]]\nx_m = {x:?}\ny_m = {y:?}\n");
        }
    } else {
        text.push_str("positions_m = [\n");
        for k in 0..n {
            let (x, y) = xy(k);
            let _ = writeln!(text, "  [{x:?}, {y:?}],");
        }
        text.push_str("]\n");
    }
    text
}

/// Write `text` as `name` in `dir`, as a case expecting `expect`.
fn write_case(dir: &Path, name: &str, expect: &str, text: &str) -> Case {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write a generated case");
    Case {
        path,
        expect: expect.to_string(),
    }
}

/// Every check on every case: library, `validate` and `run`.
fn all_problems(cases: &[Case]) -> Vec<String> {
    cases
        .iter()
        .flat_map(|case| {
            let mut problems = library_problems(case);
            problems.extend(validate_problems(case));
            problems.extend(run_problems(case));
            problems
        })
        .collect()
}

#[test]
fn the_corpus_holds_at_least_30_files_each_naming_its_field() {
    let cases = corpus();
    assert!(
        cases.len() >= MIN_CORPUS_FILES,
        "{} holds {} scenario files, fewer than {MIN_CORPUS_FILES}",
        corpus_dir().display(),
        cases.len()
    );
    // A field is a dotted path, `line L, column C` or `(file)`: never a stray comment.
    for case in &cases {
        assert!(
            !case.expect.contains(' ') || case.expect.starts_with("line "),
            "{}: `# expect: {}` does not look like a field",
            case.name(),
            case.expect
        );
    }
}

#[test]
fn the_library_names_the_expected_field_for_every_corpus_file() {
    let cases = corpus();
    let problems: Vec<String> = cases.iter().flat_map(library_problems).collect();
    assert_no_problems("Scenario::load on the corpus", cases.len(), &problems);
}

#[test]
fn coordinator_validate_refuses_every_corpus_file_with_exit_code_2_and_one_line() {
    let cases = corpus();
    let problems: Vec<String> = cases.iter().flat_map(validate_problems).collect();
    assert_no_problems("coordinator validate on the corpus", cases.len(), &problems);
}

#[test]
fn coordinator_run_refuses_every_corpus_file_before_creating_anything() {
    let cases = corpus();
    let problems: Vec<String> = cases.iter().flat_map(run_problems).collect();
    assert_no_problems("coordinator run on the corpus", cases.len(), &problems);
}

/// What is not a regular file of at most `MAX_SCENARIO_BYTES` is refused as unreadable
/// before its bytes are read, in bounded time and memory: a missing file, a folder, a
/// device (`/dev/zero` reports no length and never ends), a FIFO (opening it waits for a
/// writer), a sparse file one byte over the bound (nothing on disk, its length over).
#[test]
fn what_is_not_a_small_regular_file_is_refused_as_unreadable_before_it_is_read() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let folder = dir.path().join("a-folder.toml");
    std::fs::create_dir(&folder).expect("create the folder");
    let fifo = dir.path().join("a-fifo.toml");
    nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::from_bits_truncate(0o600)).expect("mkfifo");
    let sparse = dir.path().join("sparse.toml");
    std::fs::File::create(&sparse)
        .and_then(|f| f.set_len(shared::world::scenario::MAX_SCENARIO_BYTES + 1))
        .expect("a sparse file");
    let zero = dir.path().join("zero.toml");
    std::os::unix::fs::symlink("/dev/zero", &zero).expect("a link to /dev/zero");
    let cases = [
        dir.path().join("does-not-exist.toml"),
        folder,
        fifo,
        sparse,
        zero,
        PathBuf::from("/dev/zero"),
    ]
    .map(|path| Case {
        path,
        expect: "(file)".into(),
    });
    assert_no_problems(
        "what is not a small regular file",
        cases.len(),
        &all_problems(&cases),
    );
}

#[test]
fn more_agents_or_obstacles_than_the_wire_holds_are_refused() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let one_slot = "  { r_m = 0.0, theta_deg = 0.0 },\n";
    let cases = [
        write_case(
            dir.path(),
            "too_many_agents.toml",
            "formation.slots",
            &valid_scenario(&grid_slots(MAX_AGENTS + 1), ""),
        ),
        write_case(
            dir.path(),
            "too_many_obstacle_positions.toml",
            "obstacles",
            &valid_scenario(one_slot, &grid_obstacles(MAX_OBSTACLES + 1, false)),
        ),
        write_case(
            dir.path(),
            "too_many_obstacle_disks.toml",
            "obstacles",
            &valid_scenario(one_slot, &grid_obstacles(MAX_OBSTACLES + 1, true)),
        ),
        write_case(
            dir.path(),
            "explicit_and_random_obstacles_over_capacity.toml",
            "obstacles.random.count",
            &valid_scenario(
                one_slot,
                &format!(
                    "{}\n[obstacles.random]\ncount = 2\n",
                    grid_obstacles(MAX_OBSTACLES - 1, false)
                ),
            ),
        ),
    ];
    assert_no_problems("over capacity", cases.len(), &all_problems(&cases));
}

#[test]
fn the_capacities_themselves_are_accepted() {
    // The refusals above are at capacity + 1: the limits must not be off by one, and the
    // generated scenarios must fail for their size alone.
    let one_slot = "  { r_m = 0.0, theta_deg = 0.0 },\n";
    let agents = Scenario::parse(&valid_scenario(&grid_slots(MAX_AGENTS), ""), "agents.toml")
        .unwrap_or_else(|e| panic!("{MAX_AGENTS} agents must be accepted: {e}"));
    assert_eq!(agents.agents.len(), MAX_AGENTS);
    for as_disks in [false, true] {
        let text = valid_scenario(one_slot, &grid_obstacles(MAX_OBSTACLES, as_disks));
        let s = Scenario::parse(&text, "obstacles.toml").unwrap_or_else(|e| {
            panic!("{MAX_OBSTACLES} obstacles (disks: {as_disks}) must be accepted: {e}")
        });
        assert_eq!(s.obstacles.len(), MAX_OBSTACLES);
    }
}

#[test]
fn a_valid_file_passes_validate_so_the_refusals_mean_something() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let path = dir.path().join("valid.toml");
    std::fs::write(
        &path,
        valid_scenario(
            "  { r_m = 0.0, theta_deg = 0.0 },\n",
            &grid_obstacles(20, false),
        ),
    )
    .expect("write the valid scenario");
    let mut cmd = Command::new(support::coordinator_bin());
    cmd.arg("validate").arg(&path);
    let output = support::run_bounded(cmd).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        output.status.code(),
        Some(0),
        "coordinator validate {} must accept the control scenario; stderr: {}",
        path.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    // Each corpus file is this kind of scenario with one thing wrong; the shipped example
    // of the format parses too.
    Scenario::load(&support::repo_root().join("scenarios").join("paper.toml"))
        .unwrap_or_else(|e| panic!("the shipped paper scenario must be valid: {e}"));
}
