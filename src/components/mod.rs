//! The user-facing ECS surface: what a game puts on its camera, lights, meshes and volumes.
//!
//! Every type is `Reflect`; every field documents its unit, default, valid range and cost.
//! Invalid values are clamped by [`validate`] with one `warn!` naming the entity and the field.

mod aaps;
mod camera;
mod image_space;
mod light;
mod material;
mod photon_map;
pub mod validate;
mod volume;

pub use aaps::*;
pub use camera::*;
pub use image_space::*;
pub use light::*;
pub use material::*;
pub use photon_map::*;
pub use volume::*;
