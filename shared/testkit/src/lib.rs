//! Test and benchmark support: readers of the real inputs that the tests and the
//! benchmarks of the formation controller reuse. Not part of any shipped program.
//!
//! - [`clcbs`]: the CL-CBS benchmark instances (real obstacle fields for the controllers);
//! - [`rust_source`]: the workspace's own source read as text, for the tests of its shape.
#![warn(missing_docs)]

pub mod clcbs;
pub mod rust_source;
