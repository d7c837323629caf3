//! The tests that check what happened in a given frame (pass logs and readbacks per frame) or
//! measure the whole process (the churn test's heap). The headless renderer runs frame by frame
//! (no pipelined rendering: each frame's render follows its main-world update), so a frame's log
//! and readbacks are its own even with a second app beside it, and these tests take one GPU
//! slot like the others. The churn test alone takes both (`GPU.exclusive()`): it measures the
//! process's resident size and Rust heap.

mod aaps;
mod change;
mod churn;
mod image_space;
mod motion;
mod pay_for_use;
mod photon_map;
mod volume;
mod volume_modes;
mod webgpu;
