//! Tests of the map reader and of the outlines: the real Navigation2 maps, bad files, and
//! random grids, each outline checked against the cells by an even-odd count that does
//! not use the tracing.

use std::path::{Path, PathBuf};

use proptest::prelude::*;

use super::*;

fn maps_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/maps"))
}

/// Checks `rings` against `blocked` on a `width` x `height` grid: every ring is
/// rectilinear with corners only and no repeated corner, the signed areas add up to the
/// blocked cells, and a cell's centre is inside an odd number of rings (counted by the
/// vertical sides to its right) exactly when it is blocked.
fn check_outlines(
    width: usize,
    height: usize,
    blocked: impl Fn(usize, usize) -> bool,
    rings: &[Vec<CellCorner>],
) -> Result<(), String> {
    let mut vertical_at: Vec<Vec<usize>> = vec![Vec::new(); height];
    for (r, ring) in rings.iter().enumerate() {
        let n = ring.len();
        if n < 4 || n % 2 != 0 {
            return Err(format!("ring {r} has {n} corners"));
        }
        let mut seen = std::collections::HashSet::new();
        for k in 0..n {
            let (a, b, c) = (ring[k], ring[(k + 1) % n], ring[(k + 2) % n]);
            if !seen.insert(a) {
                return Err(format!("ring {r} repeats corner {a:?}"));
            }
            let (ab_h, bc_h) = (a[1] == b[1], b[1] == c[1]);
            if !(ab_h || a[0] == b[0]) || a == b {
                return Err(format!("ring {r}: side {a:?} -> {b:?} is not axis-aligned"));
            }
            if ab_h == bc_h {
                return Err(format!("ring {r}: {b:?} is not a corner"));
            }
            if a[0] == b[0] {
                let rows = a[1].min(b[1])..a[1].max(b[1]);
                for sides in &mut vertical_at[rows] {
                    sides.push(a[0]);
                }
            }
        }
    }
    let area2: i64 = rings.iter().map(|r| ring_area2_cells(r)).sum();
    let cells = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .filter(|&(x, y)| blocked(x, y))
        .count();
    if area2 != 2 * cells as i64 {
        return Err(format!(
            "rings enclose {area2}/2 cells, {cells} are blocked"
        ));
    }
    for (y, sides) in vertical_at.iter().enumerate() {
        for x in 0..width {
            let crossings = sides.iter().filter(|&&i| i > x).count();
            if (crossings % 2 == 1) != blocked(x, y) {
                return Err(format!("cell ({x}, {y}): {crossings} crossings"));
            }
        }
    }
    Ok(())
}

#[test]
fn the_outlines_of_the_real_maps_cover_exactly_their_blocked_cells() {
    for name in ["depot.yaml", "tb3_sandbox.yaml"] {
        let (_, grid) = OccupancyGrid::load(&maps_dir().join(name)).unwrap();
        for (what, blocked) in [
            ("occupied", (|c| c == Cell::Occupied) as fn(Cell) -> bool),
            ("not free", |c| c != Cell::Free),
        ] {
            let rings = outline_cells(grid.width, grid.height, |x, y| blocked(grid.cell(x, y)));
            assert!(rings.len() > 1, "{name}: {what}: {} rings", rings.len());
            check_outlines(
                grid.width,
                grid.height,
                |x, y| blocked(grid.cell(x, y)),
                &rings,
            )
            .unwrap_or_else(|e| panic!("{name}: {what}: {e}"));
        }
    }
}

#[test]
fn the_real_maps_read_as_the_map_server_reads_them() {
    let (yaml, depot) = OccupancyGrid::load(&maps_dir().join("depot.yaml")).unwrap();
    assert_eq!(yaml.image, maps_dir().join("depot.pgm"));
    assert_eq!((depot.width, depot.height), (604, 307));
    let (yaml, tb3) = OccupancyGrid::load(&maps_dir().join("tb3_sandbox.yaml")).unwrap();
    assert_eq!((yaml.origin_m, yaml.free_thresh), ([-10.0, -10.0], 0.196));
    // The map_server's own grey for unknown (205) is unknown at this free threshold:
    // (255 - 205) / 255 = 0.19608 > 0.196. Its corners are unmapped.
    assert_eq!(tb3.cell(0, 0), Cell::Unknown);
    let raster = Raster::read(&maps_dir().join("tb3_sandbox.pgm")).unwrap();
    assert_eq!(
        (raster.width, raster.height, raster.max_value),
        (384, 384, 255)
    );
    // Row 0 of the grid is the image's last row.
    let bottom = raster.pixel(0, raster.height - 1)[0];
    assert_eq!(bottom, 205);
    // Cells read off the image by an independent script: a wall cell whose mirror row
    // (the image unflipped) is free, and a free cell whose mirror row is unknown.
    assert_eq!(tb3.cell(175, 154), Cell::Occupied);
    assert_eq!(tb3.cell(175, 383 - 154), Cell::Free);
    assert_eq!(tb3.cell(177, 162), Cell::Free);
    assert_eq!(tb3.cell(177, 383 - 162), Cell::Unknown);
    // The image's histogram: 870 black, 7 903 white, the rest unknown grey.
    assert_eq!(tb3.count(Cell::Occupied), 870);
    assert_eq!(tb3.count(Cell::Free), 7903);
    assert_eq!(depot.count(Cell::Occupied), 5947);
    // The depot's free threshold is 0.25: its 8 894 grey (205) pixels read as free.
    assert_eq!(depot.count(Cell::Free), 170_587 + 8_894);
    // Cell centres and the cell at a point agree.
    let p = tb3.cell_centre(17, 301);
    assert_eq!(tb3.cell_at(&p), Some([17, 301]));
    assert_eq!(tb3.cell_at(&Point::new(-10.1, 0.0)), None);
}

use crate::geometry::Point;

fn yaml_with(image: &str, mode: &str, negate: u8, free: f64, occupied: f64) -> MapYaml {
    let text = format!(
        "image: {image}\nmode: {mode}\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: {negate}\n\
         occupied_thresh: {occupied}\nfree_thresh: {free}\n"
    );
    MapYaml::parse(&text, "m.yaml", Path::new("")).unwrap()
}

#[test]
fn shades_become_cells_by_mode_and_thresholds() {
    // Grey values 0, 254, 205, 100 in one row.
    let raster = Raster {
        width: 4,
        height: 1,
        max_value: 255,
        channels: 1,
        samples: vec![0, 254, 205, 100],
    };
    let cells = |yaml: &MapYaml| {
        let g = OccupancyGrid::from_raster(&raster, yaml);
        (0..4).map(|x| g.cell(x, 0)).collect::<Vec<_>>()
    };
    use Cell::*;
    assert_eq!(
        cells(&yaml_with("a.pgm", "trinary", 0, 0.25, 0.65)),
        [Occupied, Free, Free, Unknown]
    );
    assert_eq!(
        cells(&yaml_with("a.pgm", "trinary", 0, 0.196, 0.65)),
        [Occupied, Free, Unknown, Unknown]
    );
    // Negated: white is occupied.
    assert_eq!(
        cells(&yaml_with("a.pgm", "trinary", 1, 0.25, 0.65)),
        [Free, Occupied, Occupied, Unknown]
    );
    // Raw: the value is a percentage; above 100 unknown.
    assert_eq!(
        cells(&yaml_with("a.pgm", "raw", 0, 0.25, 0.65)),
        [Free, Unknown, Unknown, Occupied]
    );
    // With alpha: scale makes a translucent pixel unknown; trinary averages alpha in.
    let with_alpha = Raster {
        width: 2,
        height: 1,
        max_value: 255,
        channels: 2,
        samples: vec![0, 255, 0, 128],
    };
    let g = OccupancyGrid::from_raster(&with_alpha, &yaml_with("a.png", "scale", 0, 0.25, 0.65));
    assert_eq!((g.cell(0, 0), g.cell(1, 0)), (Occupied, Unknown));
    let g = OccupancyGrid::from_raster(&with_alpha, &yaml_with("a.png", "trinary", 0, 0.25, 0.65));
    // (0 + 255) / 2 / 255 = 0.5 shade, 0.5 occupancy: unknown; (0 + 128) / 2: 0.749 occupied.
    assert_eq!((g.cell(0, 0), g.cell(1, 0)), (Unknown, Occupied));
}

#[test]
fn plain_and_sixteen_bit_pgm_and_png_images_read_alike() {
    let binary = Raster::decode(b"P5\n3 2\n255\n\x00\x10\x20\x30\x40\xff").unwrap();
    let plain = Raster::decode(b"P2\n# a comment\n3 2\n255\n0 16 32\n48 64 255\n").unwrap();
    assert_eq!(binary, plain);
    let wide = Raster::decode(b"P5 1 1 65535\n\x12\x34").unwrap();
    assert_eq!(
        (wide.max_value, wide.samples.as_slice()),
        (65535, &[0x1234u16][..])
    );
    // The same pixels as a PNG, written by the png crate.
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, 3, 2);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer
            .write_image_data(&[0x00, 0x10, 0x20, 0x30, 0x40, 0xff])
            .unwrap();
    }
    assert_eq!(Raster::decode(&bytes).unwrap(), binary);
}

#[test]
fn images_whose_header_lies_are_refused_with_the_reason() {
    let cases: [(&[u8], &str); 9] = [
        (
            b"P5\n3 2\n255\n\x00\x10",
            "3 x 2 pixels (6 bytes) but 2 bytes follow",
        ),
        (
            b"P5\n1 1\n255\n\x00\x00",
            "1 x 1 pixels (1 bytes) but 2 bytes follow",
        ),
        (b"P5\n1 1\n100\n\xff", "exceeds the PGM's maxval 100"),
        (b"P5\n1 1\n0\n\x00", "maxval 0 is not within"),
        (b"P5\n0 1\n255\n", "holds no cell"),
        (
            b"P5\n5000 5000\n255\n",
            "exceed the limit of 16777216 cells",
        ),
        (
            b"P2\n2 1\n255\n7\n",
            "ends before its samples (1 of the 2 x 1",
        ),
        (b"P5\nx 1\n255\n", "width is not a number"),
        (b"GIF89a", "not a PGM (P5 or P2) or PNG image"),
    ];
    for (bytes, says) in cases {
        let e = Raster::decode(bytes).unwrap_err();
        assert!(
            e.contains(says),
            "{:?}: {e}",
            String::from_utf8_lossy(bytes)
        );
    }
    let e = Raster::decode(b"\x89PNG\r\n\x1a\n\x00\x00").unwrap_err();
    assert!(e.starts_with("not a readable PNG"), "{e}");
}

/// A folder of this test process's own, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("occupancy-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn bad_map_files_are_refused_naming_the_file_and_the_field() {
    let dir = Scratch::new("bad");
    let good = "image: m.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n\
                occupied_thresh: 0.65\nfree_thresh: 0.25\n";
    std::fs::write(dir.0.join("m.pgm"), b"P5 2 1 255\n\x00\xff").unwrap();
    let yaml = dir.0.join("m.yaml");
    let load = |text: &str| {
        std::fs::write(&yaml, text).unwrap();
        OccupancyGrid::load(&yaml).map(|(_, g)| g)
    };
    let g = load(good).unwrap();
    assert_eq!((g.cell(0, 0), g.cell(1, 0)), (Cell::Occupied, Cell::Free));
    let f = yaml.display().to_string();
    let image = dir.0.join("none.pgm").display().to_string();
    let cases = [
        (
            good.replace("m.pgm", "none.pgm"),
            format!("{image}: (image): "),
        ),
        (
            format!("{good}colour: red\n"),
            format!("{f}: line 7: unknown field `colour`"),
        ),
        (
            good.replace("negate: 0\n", ""),
            format!("{f}: negate: missing"),
        ),
        (
            good.replace("0.25", "0.7"),
            format!("{f}: free_thresh: 0.7 must be below"),
        ),
        (
            good.replace("0.65", "1.5"),
            format!("{f}: occupied_thresh: must be within [0, 1]"),
        ),
        (
            good.replace("0.05", "-1"),
            format!("{f}: resolution: must be a positive"),
        ),
        (
            good.replace("0.0, 0.0, 0.0", "0, 0, 1.57"),
            format!("{f}: origin: a rotated map"),
        ),
        (
            good.replace("0.0, 0.0, 0.0", "0, 0"),
            format!("{f}: origin: must be [x, y, yaw]"),
        ),
        (
            good.replace("negate: 0", "negate: 2"),
            format!("{f}: negate: must be 0 or 1"),
        ),
        (
            format!("{good}mode: fuzzy\n"),
            format!("{f}: mode: \"fuzzy\" is not one of"),
        ),
        (
            good.replace("image: m.pgm", "image: ''"),
            format!("{f}: image: is empty"),
        ),
    ];
    for (text, says) in cases {
        let e = load(&text).unwrap_err().to_string();
        assert!(e.starts_with(&says), "{text}\n -> {e}\n expected {says}");
        assert_eq!(e.lines().count(), 1, "{e}");
    }
    std::fs::write(dir.0.join("m.pgm"), b"P5 3 1 255\n\x00\xff").unwrap();
    let e = load(good).unwrap_err();
    assert_eq!(e.field(), "(image)");
    assert!(
        e.to_string()
            .contains("3 x 1 pixels (3 bytes) but 2 bytes follow"),
        "{e}"
    );
    let e = OccupancyGrid::load(&dir.0).unwrap_err();
    assert!(e.to_string().contains("is a folder"), "{e}");
}

#[test]
fn cells_meeting_at_a_corner_are_separate_rings_and_holes_run_clockwise() {
    // A 4 x 4 checkerboard: eight rings of one cell each.
    let rings = outline_cells(4, 4, |x, y| (x + y) % 2 == 0);
    assert_eq!(rings.len(), 8);
    assert!(
        rings
            .iter()
            .all(|r| r.len() == 4 && ring_area2_cells(r) == 2)
    );
    // A 3 x 3 block with a free centre: its outer boundary and a clockwise hole.
    let rings = outline_cells(3, 3, |x, y| (x, y) != (1, 1));
    let mut areas: Vec<i64> = rings.iter().map(|r| ring_area2_cells(r)).collect();
    areas.sort();
    assert_eq!(areas, [-2, 18]);
    // A ring of cells closed only by two cells meeting at corner [2, 2]: the free centre
    // is enclosed, the boundary pinched at that corner becomes two simple loops.
    let rings = outline_cells(3, 3, |x, y| !matches!((x, y), (1, 1) | (2, 2)));
    check_outlines(3, 3, |x, y| !matches!((x, y), (1, 1) | (2, 2)), &rings).unwrap();
    let mut areas: Vec<i64> = rings.iter().map(|r| ring_area2_cells(r)).collect();
    areas.sort();
    assert_eq!(areas, [-2, 16]);
    assert!(rings.iter().all(|r| r.contains(&[2, 2])));
    // Nothing blocked, nothing drawn; everything blocked, one rectangle.
    assert!(outline_cells(5, 3, |_, _| false).is_empty());
    assert_eq!(
        outline_cells(5, 3, |_, _| true),
        vec![vec![[0, 0], [5, 0], [5, 3], [0, 3]]]
    );
}

/// Checks `pieces` against the cells of `grid` for which `blocked` holds: every piece is
/// a simple polygon (checked in full by [`Polygon::new`]) of the same area, the areas add
/// up to the blocked cells', and every cell's centre lies in exactly one piece when the
/// cell is blocked and in none when it is not (so the pieces cover the blocked cells
/// exactly, without overlapping).
fn check_pieces(
    grid: &OccupancyGrid,
    blocked: impl Fn(Cell) -> bool,
    pieces: &[crate::geometry::Polygon],
) -> Result<(), String> {
    let res = grid.resolution_m;
    let mut inside = vec![0u32; grid.width * grid.height];
    let mut area_m2 = 0.0;
    for (k, piece) in pieces.iter().enumerate() {
        let checked = crate::geometry::Polygon::new(piece.vertices().to_vec())
            .map_err(|e| format!("piece {k}: {e}"))?;
        if checked.area_m2() != piece.area_m2() || piece.area_m2() <= 0.0 {
            return Err(format!("piece {k}: area {}", piece.area_m2()));
        }
        area_m2 += piece.area_m2();
        let cell = |v: f64, o: f64| ((v - o) / res).round() as usize;
        let xs = piece.vertices().iter().map(|p| cell(p.x, grid.origin_m[0]));
        let ys = piece.vertices().iter().map(|p| cell(p.y, grid.origin_m[1]));
        let (x0, x1) = (xs.clone().min().unwrap_or(0), xs.max().unwrap_or(0));
        let (y0, y1) = (ys.clone().min().unwrap_or(0), ys.max().unwrap_or(0));
        for y in y0..y1.min(grid.height) {
            for x in x0..x1.min(grid.width) {
                if piece.contains(&grid.cell_centre(x, y)) {
                    inside[y * grid.width + x] += 1;
                }
            }
        }
    }
    let mut cells = 0;
    for y in 0..grid.height {
        for x in 0..grid.width {
            let want = u32::from(blocked(grid.cell(x, y)));
            cells += want;
            if inside[y * grid.width + x] != want {
                return Err(format!(
                    "cell ({x}, {y}) is in {} pieces, blocked: {}",
                    inside[y * grid.width + x],
                    want == 1
                ));
            }
        }
    }
    let blocked_m2 = f64::from(cells) * res * res;
    if (area_m2 - blocked_m2).abs() > 1e-9 * blocked_m2.max(1.0) {
        return Err(format!(
            "pieces cover {area_m2} m2, blocked cells {blocked_m2} m2"
        ));
    }
    Ok(())
}

#[test]
fn the_pieces_of_the_real_maps_are_simple_and_cover_exactly_their_blocked_cells() {
    for name in ["depot.yaml", "tb3_sandbox.yaml"] {
        let (_, grid) = OccupancyGrid::load(&maps_dir().join(name)).unwrap();
        for (what, blocked) in [
            ("occupied", (|c| c == Cell::Occupied) as fn(Cell) -> bool),
            ("not free", |c| c != Cell::Free),
        ] {
            let pieces = grid.pieces(blocked);
            assert!(pieces.len() > 1, "{name}: {what}: {} pieces", pieces.len());
            check_pieces(&grid, blocked, &pieces).unwrap_or_else(|e| panic!("{name}: {what}: {e}"));
        }
    }
}

#[test]
fn a_ring_of_walls_is_cut_until_no_piece_has_a_hole() {
    // A 20 x 20 room: walls one cell thick round a free floor, inside one tile row of
    // 16 and beyond it, so the first tile's outline has a hole and must be cut.
    let n = 20;
    let cells = (0..n * n)
        .map(|k| {
            let (x, y) = (k % n, k / n);
            match x == 0 || y == 0 || x == n - 1 || y == n - 1 {
                true => Cell::Occupied,
                false => Cell::Free,
            }
        })
        .collect();
    let grid = OccupancyGrid::from_cells(n, n, 0.5, [-1.0, 2.0], cells);
    let pieces = grid.pieces(|c| c == Cell::Occupied);
    check_pieces(&grid, |c| c == Cell::Occupied, &pieces).unwrap();
    // The pieces are grown obstacles as they are: the floor's middle is free and 4.5 m
    // from every wall (each wall piece's inner side at 0.5 m from the map's edge).
    let middle = Point::new(-1.0 + 5.0, 2.0 + 5.0);
    let nearest = pieces
        .iter()
        .map(|p| p.distance_m(&middle))
        .fold(f64::INFINITY, f64::min);
    assert_eq!(nearest, 4.5);
    // A path bends only round the room's four outer corners: the corners where the wall
    // was cut into pieces are seams, and the floor's corners are not convex.
    let mut bends: Vec<(f64, f64)> = pieces
        .iter()
        .flat_map(|p| {
            p.bend_corners()
                .map(|i| (p.vertices()[i].x, p.vertices()[i].y))
        })
        .collect();
    bends.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(bends, [(-1.0, 2.0), (-1.0, 12.0), (9.0, 2.0), (9.0, 12.0)]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn the_pieces_of_random_grids_cover_exactly_their_blocked_cells(
        width in 1usize..40,
        height in 1usize..40,
        density in 0.3f64..0.95,
        seed in any::<u64>(),
    ) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let cells: Vec<Cell> = (0..width * height)
            .map(|_| if rng.random_bool(density) { Cell::Occupied } else { Cell::Free })
            .collect();
        let grid = OccupancyGrid::from_cells(width, height, 0.05, [1.0, -2.0], cells);
        let pieces = grid.pieces(|c| c == Cell::Occupied);
        let checked = check_pieces(&grid, |c| c == Cell::Occupied, &pieces);
        prop_assert!(checked.is_ok(), "{:?}", checked);
    }

    #[test]
    fn the_outlines_of_random_grids_cover_exactly_their_blocked_cells(
        width in 1usize..14,
        height in 1usize..14,
        density in 0.05f64..0.95,
        seed in any::<u64>(),
    ) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let cells: Vec<bool> = (0..width * height).map(|_| rng.random_bool(density)).collect();
        let blocked = |x: usize, y: usize| cells[y * width + x];
        let rings = outline_cells(width, height, blocked);
        prop_assert!(check_outlines(width, height, blocked, &rings).is_ok(),
            "{:?}", check_outlines(width, height, blocked, &rings));
    }
}
