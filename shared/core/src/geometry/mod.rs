//! Plane geometry shared by every controller: points, disks, polylines, simple polygons
//! and polygons grown by a radius,
//! the rectangular field, and uniform-grid spatial indexes over disks and boxes.
//!
//! Everything is `f64` and uses nalgebra's `Point2`/`Vector2`, the same types parry2d-f64
//! uses, so there is one vector type in the whole system.

/// A point of the plane, in metres.
pub type Point = nalgebra::Point2<f64>;
/// A displacement in the plane, in metres.
pub type Vector = nalgebra::Vector2<f64>;

mod box_index;
mod cell_lists;
mod disk;
mod disk_grid;
mod field;
mod free_space;
mod inflated_polygon;
mod intersections;
mod polygon;
mod polygon_layer;
mod polyline;
mod pose;
mod region_grid;

pub use box_index::BoxIndex;
pub use disk::{Disk, distance_point_segment};
pub use disk_grid::DiskGrid;
pub use field::Field;
pub use free_space::FreeSpace;
pub use inflated_polygon::InflatedPolygon;
pub use intersections::{
    circle_circle_intersections, circle_line_intersections, line_line_intersection,
};
pub use polygon::{Polygon, PolygonError};
pub use polygon_layer::PolygonLayer;
pub use polyline::{
    distance_at_the_same_time_m, distance_polyline_polyline, distance_segment_segment,
    polyline_length_m, polyline_prefix, relative_motion,
};
pub use pose::{Pose, wrap_angle_rad};
pub use region_grid::RegionGrid;

#[cfg(test)]
mod tests;
