//! What the GPU test binaries share: the lock that runs their Bevy apps one at a time, the
//! adapter check, the examples' executables and a global allocator that counts the Rust heap.

use std::path::PathBuf;
use std::sync::Mutex;

use bevy_caustics::headless::find_adapter;

/// Bevy apps run one at a time, each on a small target.
pub static GPU: Mutex<()> = Mutex::new(());

/// `true` with a Vulkan adapter; without one, a panic (or `false`, a skip, only where
/// BEVY_CAUSTICS_ALLOW_NO_GPU is set: a developer machine).
pub fn require_gpu() -> bool {
    match find_adapter() {
        Ok(name) => {
            println!("adapter: {name}");
            true
        }
        Err(e) if std::env::var_os("BEVY_CAUSTICS_ALLOW_NO_GPU").is_some() => {
            println!("skipped: {e}");
            false
        }
        Err(e) => panic!("{e}"),
    }
}

/// The built example `name` (cargo builds the examples before the tests).
pub fn example_exe(name: &str) -> PathBuf {
    // target/release/deps/<test>-* -> target/release/examples/<name>
    let exe = std::env::current_exe().unwrap();
    exe.parent()
        .unwrap()
        .parent()
        .unwrap()
        .join("examples")
        .join(name)
}

/// The system allocator, counting the bytes Rust code holds (ours, Bevy's, wgpu's). A leak in
/// Rust code shows here; the Vulkan driver allocates with C's malloc and does not, so the count
/// tells a leak of ours from lavapipe's own growth, which dominates the resident size.
pub struct CountingAllocator;

static RUST_HEAP: std::sync::atomic::AtomicIsize = std::sync::atomic::AtomicIsize::new(0);

/// Bytes allocated by Rust code and not yet freed.
#[allow(dead_code)]
pub fn rust_heap_bytes() -> i64 {
    RUST_HEAP.load(std::sync::atomic::Ordering::Relaxed) as i64
}

// SAFETY: every call forwards to `System` unchanged; the counter is only arithmetic.
unsafe impl std::alloc::GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        RUST_HEAP.fetch_add(layout.size() as isize, std::sync::atomic::Ordering::Relaxed);
        // SAFETY: the caller's contract, passed on.
        unsafe { std::alloc::System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        RUST_HEAP.fetch_add(layout.size() as isize, std::sync::atomic::Ordering::Relaxed);
        // SAFETY: the caller's contract, passed on.
        unsafe { std::alloc::System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        RUST_HEAP.fetch_sub(layout.size() as isize, std::sync::atomic::Ordering::Relaxed);
        // SAFETY: the caller's contract, passed on.
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, size: usize) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        let p = unsafe { std::alloc::System.realloc(ptr, layout, size) };
        if !p.is_null() {
            RUST_HEAP.fetch_add(
                size as isize - layout.size() as isize,
                std::sync::atomic::Ordering::Relaxed,
            );
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;
