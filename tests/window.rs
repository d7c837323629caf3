//! The window tests (`tests/gpu/window.rs`: the README's app in a real window under Xvfb) and
//! the sample models written by others (`tests/gpu/assets.rs`) in a process of their own. The
//! GPU tests' process grows with every Bevy app it starts (about 20 GB by its last test on a
//! 24 GB machine); the window tests start example processes, which then found too little
//! memory left, and the six sample-model apps took that process past the machine's 23 GB
//! (killed for memory at 24.2 GB, clean clone, stop 56).

#[path = "gpu/assets.rs"]
mod assets;
#[path = "gpu/support.rs"]
mod support;
#[path = "gpu/window.rs"]
mod window;

use support::{GPU, require_gpu};
