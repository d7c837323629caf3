//! The tests that take both GPU slots (`GPU.exclusive()`): those that measure the whole process
//! (the churn test's heap) or check what happened in a given frame (pass logs and readbacks per
//! frame, which a second app beside them can shift under Bevy's pipelined rendering). They
//! live here, one file per feature, so that they run back to back: libtest starts tests in
//! the order of their names, and an exclusive test that starts beside a one-slot test waits
//! for it with one core idle (measured: 15 such tests spread over the binary waited up to
//! 97 s each; see docs/testing.md).

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
