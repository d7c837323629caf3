//! Caustics volumes (seed 000): the plain-Rust core of the `Volume` technique — the photon
//! state of the seed's table 2 and the seeding of the entry face (section 3.4), the volume's
//! frame, slab probes and projectors ([`VolumeFrame`]), and the splat footprint. The GPU passes
//! are in `crate::render::volume`.

mod extras;
mod frame;
mod gizmo;
mod progressive;
mod seed;
mod splat;

pub use extras::*;
pub use frame::*;
pub use gizmo::*;
pub use progressive::*;
pub use seed::*;
pub use splat::*;
