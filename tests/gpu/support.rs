//! What the GPU test binaries share: the slots that run their Bevy apps two at a time, the
//! adapter check, the examples' executables and a global allocator that counts the Rust heap.

use std::path::PathBuf;
use std::sync::{Condvar, Mutex};

use bevy_caustics::headless::find_adapter;

/// Bevy apps run at most two at a time, each on a small target: an app's start-up (plugins,
/// shaders, pipelines) is mostly one CPU thread, so on CI's 2 cores two apps side by side
/// finish 1.6 times sooner than one after the other (measured: four 32x32 renders, 8.4 s in
/// turn, 5.2 s two at a time). A test that measures the whole process (its heap) takes both,
/// and so does one that checks what happened in a given frame: under Bevy's pipelined
/// rendering the render world runs beside the main world's next frame, and on a loaded machine
/// one frame's pass log or readback can then hold another frame's (measured: a stereo test's
/// frame held two render frames' passes, an energy comparison moved by 0.7 %).
pub static GPU: GpuSlots = GpuSlots::new(2);

/// A counting semaphore for the GPU tests' Bevy apps.
pub struct GpuSlots {
    total: usize,
    /// (free slots, tests waiting for all of them)
    state: Mutex<(usize, usize)>,
    changed: Condvar,
}

/// Held while a test runs its apps; gives its slots back when dropped (also on a panic).
pub struct GpuSlot<'a> {
    slots: &'a GpuSlots,
    taken: usize,
}

impl GpuSlots {
    const fn new(total: usize) -> Self {
        Self {
            total,
            state: Mutex::new((total, 0)),
            changed: Condvar::new(),
        }
    }

    /// One slot: the test's apps may run beside one other test's.
    #[allow(dead_code)]
    pub fn slot(&self) -> GpuSlot<'_> {
        self.take(1)
    }

    /// Every slot: nothing else runs (a test that measures the process). Tests asking for
    /// one slot wait while this one waits, so it is not starved.
    #[allow(dead_code)]
    pub fn exclusive(&self) -> GpuSlot<'_> {
        self.take(self.total)
    }

    fn take(&self, n: usize) -> GpuSlot<'_> {
        let asked = std::time::Instant::now();
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let all = n == self.total;
        if all {
            state.1 += 1;
        }
        while state.0 < n || (!all && state.1 > 0) {
            state = self.changed.wait(state).unwrap_or_else(|e| e.into_inner());
        }
        state.0 -= n;
        if all {
            state.1 -= 1;
        }
        drop(state);
        report_wait(n, asked.elapsed());
        GpuSlot {
            slots: self,
            taken: n,
        }
    }
}

/// A wait of over a second, written to the process's stderr past libtest's capture (CI's log
/// shows where the two slots stood idle): the test, the slots it asked for, and the seconds.
fn report_wait(n: usize, waited: std::time::Duration) {
    use std::io::Write;
    if waited.as_secs_f64() > 1.0 {
        let test = std::thread::current().name().unwrap_or("?").to_string();
        let line = format!(
            "gpu slots: {test} waited {:.1} s for {n} slot(s)\n",
            waited.as_secs_f64()
        );
        let _ = std::io::stderr().write_all(line.as_bytes());
    }
}

impl Drop for GpuSlot<'_> {
    fn drop(&mut self) {
        let mut state = self.slots.state.lock().unwrap_or_else(|e| e.into_inner());
        state.0 += self.taken;
        self.slots.changed.notify_all();
    }
}

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
