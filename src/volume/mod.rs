//! Caustics volumes (seed 000): the plain-Rust core of the `Volume` technique. This version
//! has the photon state of the seed's table 2 and the seeding of the entry face (section 3.4);
//! slab propagation, projectors and splatting are not implemented yet.

mod seed;

pub use seed::*;
