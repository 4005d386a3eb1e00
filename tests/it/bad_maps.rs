//! Maps handed in that are wrong: `coordinator validate MAP.yaml` and a scenario's map
//! refused with exit code 2 and one line naming the file and the field, as a malformed
//! scenario is (`bad_input.rs`); maps too large to build refused before they are built.

use std::path::PathBuf;
use std::process::Command;

use crate::bad_input::{Case, refusal_problems};
use crate::support;

/// `coordinator validate MAP.yaml` reads a real map and says what it holds; a map with
/// one thing wrong (in the YAML or in its image) is refused with exit code 2 and one line
/// naming the file and the field, as a scenario is.
#[test]
fn coordinator_validate_reads_a_real_map_and_refuses_bad_ones_with_one_line() {
    let maps = support::repo_root().join("shared/core/tests/data/maps");
    let mut cmd = Command::new(support::coordinator_bin());
    cmd.arg("validate").arg(maps.join("depot.yaml"));
    let output = support::run_bounded(cmd).unwrap_or_else(|e| panic!("{e}"));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("604 x 307 cells of 0.05 m") && stderr.contains("5947 occupied"),
        "{stderr}"
    );

    let dir = tempfile::tempdir().expect("temporary folder");
    let good = "image: m.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n\
                occupied_thresh: 0.65\nfree_thresh: 0.25\n";
    std::fs::write(dir.path().join("m.pgm"), b"P5 2 2 255\n\x00\xfe\xfe\xfe").expect("pgm");
    std::fs::write(dir.path().join("short.pgm"), b"P5 2 2 255\n\x00\xfe").expect("pgm");
    let image = |name: &str| dir.path().join(name).display().to_string();
    // The YAML itself a FIFO or a device: refused as unreadable.
    let yaml_fifo = dir.path().join("a-fifo.yaml");
    nix::unistd::mkfifo(&yaml_fifo, nix::sys::stat::Mode::from_bits_truncate(0o600))
        .expect("mkfifo");
    let yaml_device = dir.path().join("device-map.yaml");
    std::os::unix::fs::symlink("/dev/zero", &yaml_device).expect("a link to /dev/zero");
    for path in [yaml_fifo, yaml_device] {
        let mut cmd = Command::new(support::coordinator_bin());
        cmd.arg("validate").arg(&path);
        let output = support::run_bounded(cmd).unwrap_or_else(|e| panic!("{e}"));
        let case = Case {
            path,
            expect: "(file)".into(),
        };
        let problems = refusal_problems("validate", &case, &output);
        assert!(problems.is_empty(), "{}", problems.join("\n"));
    }
    let cases = [
        (
            "missing-key.yaml",
            good.replace("negate: 0\n", ""),
            "negate",
            None,
        ),
        (
            "unknown-key.yaml",
            format!("{good}colour: red\n"),
            "line 7",
            None,
        ),
        (
            "thresholds.yaml",
            good.replace("0.25", "0.9"),
            "free_thresh",
            None,
        ),
        (
            "rotated.yaml",
            good.replace("0.0, 0.0, 0.0", "0, 0, 0.5"),
            "origin",
            None,
        ),
        (
            "no-image.yaml",
            good.replace("m.pgm", "none.pgm"),
            "(image)",
            Some("none.pgm"),
        ),
        (
            "short.yaml",
            good.replace("m.pgm", "short.pgm"),
            "(image)",
            Some("short.pgm"),
        ),
        // An image that is a device or a FIFO: refused before a byte is read.
        (
            "device.yaml",
            good.replace("m.pgm", "/dev/zero"),
            "(image)",
            Some("/dev/zero"),
        ),
        (
            "fifo.yaml",
            good.replace("m.pgm", "fifo.pgm"),
            "(image)",
            Some("fifo.pgm"),
        ),
    ];
    nix::unistd::mkfifo(
        &dir.path().join("fifo.pgm"),
        nix::sys::stat::Mode::from_bits_truncate(0o600),
    )
    .expect("mkfifo");
    let mut problems = Vec::new();
    for (name, text, field, in_image) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).expect("write a bad map");
        // Image errors name the image; the others the YAML file.
        let named = Case {
            path: in_image.map_or(path.clone(), |i| PathBuf::from(image(i))),
            expect: field.to_string(),
        };
        let mut cmd = Command::new(support::coordinator_bin());
        cmd.arg("validate").arg(&path);
        match support::run_bounded(cmd) {
            Ok(output) => problems.extend(refusal_problems("validate", &named, &output)),
            Err(e) => problems.push(e),
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The control map of the bad ones passes.
    let path = dir.path().join("good.yaml");
    std::fs::write(&path, good).expect("write the good map");
    let mut cmd = Command::new(support::coordinator_bin());
    cmd.arg("validate").arg(&path);
    let output = support::run_bounded(cmd).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(output.status.code(), Some(0), "{output:?}");
}

/// A controller that does not plan round polygons yet, asked for by name on a scenario
/// with polygons, is refused before anything runs: exit 2, one line, no folder.
#[test]
fn a_controller_that_does_not_see_polygons_is_refused_on_a_polygon_scenario() {
    let scenario = support::repo_root().join("scenarios/polygon-corridor.toml");
    let dir = tempfile::tempdir().expect("temporary folder");
    for command in ["run", "simulate"] {
        let out = dir.path().join(command);
        let mut cmd = Command::new(support::coordinator_bin());
        cmd.arg(command)
            .arg(&scenario)
            .args(["--controller", "orca"]);
        if command == "run" {
            cmd.arg("--out").arg(&out);
        }
        let output = support::run_bounded(cmd).unwrap_or_else(|e| panic!("{e}"));
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{command}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{command}: {stderr}");
        assert!(
            stderr.contains("controller orca") && stderr.contains("polygon"),
            "{stderr}"
        );
        assert!(!out.exists(), "{command}: nothing written");
    }
}

/// `validate` on a scenario with a map names the map and its pieces in its one line,
/// beside the polygons drawn by hand (none here), and exits 0.
#[test]
fn validate_names_a_scenarios_map_and_its_pieces() {
    let scenario = support::repo_root().join("scenarios/depot-shelves.toml");
    let mut cmd = Command::new(support::coordinator_bin());
    cmd.arg("validate").arg(&scenario);
    let output = support::run_bounded(cmd).unwrap_or_else(|e| panic!("{e}"));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("valid: 4 agents, 0 obstacles, a map of 604 x 307 cells cut into ")
            && !stderr.contains("polygons,"),
        "{stderr}"
    );
}

/// A map whose blocked cells make millions of pieces (a 4096 x 4096 checkerboard: one
/// piece of every other cell) is refused in one line once the count passes the limit,
/// before the rest are built: the refusal fits in 512 MiB of address space (building
/// them all took about 1.9 GB).
#[test]
fn a_map_of_millions_of_pieces_is_refused_before_they_are_built() {
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().expect("temporary folder");
    let side = 4096;
    let mut pgm = format!("P5\n{side} {side}\n255\n").into_bytes();
    for y in 0..side {
        pgm.extend((0..side).map(|x| if (x + y) % 2 == 0 { 0u8 } else { 255 }));
    }
    std::fs::write(dir.path().join("checker.pgm"), pgm).expect("pgm");
    std::fs::write(
        dir.path().join("checker.yaml"),
        "image: checker.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n\
         occupied_thresh: 0.65\nfree_thresh: 0.25\n",
    )
    .expect("yaml");
    let scenario = dir.path().join("checker.toml");
    std::fs::write(
        &scenario,
        "name = \"checker\"\n[map]\nyaml = \"checker.yaml\"\n[formation]\n\
         agent_radius_m = 0.2\nslots = [{ r_m = 0.0, theta_deg = 0.0 }]\n[path]\n\
         start = { x_m = 4.0, y_m = 7.5, heading_deg = 0.0 }\n\
         goal = { x_m = 28.6, y_m = 4.35, heading_deg = 0.0 }\n\
         turning_radius_m = 1.0\nstep_m = 0.25\ncentre_clearance_m = 0.3\n",
    )
    .expect("scenario");
    let mut cmd = Command::new(support::coordinator_bin());
    cmd.arg("validate").arg(&scenario);
    // SAFETY: setrlimit(2) between fork and exec, on a value made before.
    unsafe {
        cmd.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 512 << 20,
                rlim_max: 512 << 20,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &limit) < 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let output = support::run_bounded(cmd).unwrap_or_else(|e| panic!("{e}"));
    let case = Case {
        path: scenario,
        expect: "map.yaml".into(),
    };
    let problems = refusal_problems("validate", &case, &output);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(
        String::from_utf8_lossy(&output.stderr).contains("pieces"),
        "{output:?}"
    );
}
