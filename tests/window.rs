//! The window tests (`tests/gpu/window.rs`: the README's app in a real window under Xvfb) in a
//! process of their own. The GPU tests' process grows with every Bevy app it starts (about
//! 20 GB by its last test on a 24 GB machine); these tests start example processes, which then
//! found too little memory left.

#[path = "gpu/support.rs"]
mod support;
#[path = "gpu/window.rs"]
mod window;

use support::{GPU, require_gpu};
