//! Main-world scene gathering: which meshes are casters and receivers, with what surface,
//! and the CPU BVH over them (rebuilt only for meshes that changed).

pub mod bvh;
pub mod change;
pub mod collect;
pub mod forward;
pub mod gpu;
pub mod model;
pub mod shape;

pub use bvh::{Blas, Hit, Instance, MeshGeometry, Tlas};
pub use collect::{CausticsScene, ScenePlugin};
pub use gpu::GpuBvh;
pub use model::*;
