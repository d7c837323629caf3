//! The adapter seen before Bevy starts (its name and limits, so a machine without one gets a
//! one-line error), the headless environment, and the decoding of frame readbacks.

use crate::limits::CausticsLimits;

/// Strip the 256-byte row padding of a texture readback, if present.
pub(crate) fn unpad_rows(data: &[u8], w: u32, h: u32, bpp: usize) -> Vec<u8> {
    let row = w as usize * bpp;
    let padded = row.div_ceil(256) * 256;
    if data.len() == padded * h as usize && padded != row {
        data.chunks(padded)
            .flat_map(|r| r[..row].iter().copied())
            .collect()
    } else {
        data.to_vec()
    }
}

fn f16_to_f32(b: u16) -> f32 {
    let s = if b & 0x8000 != 0 { -1.0 } else { 1.0 };
    let e = ((b >> 10) & 0x1f) as i32;
    let m = (b & 0x3ff) as f32;
    match e {
        0 => s * m * 2f32.powi(-24),
        31 => {
            if m == 0.0 {
                s * f32::INFINITY
            } else {
                f32::NAN
            }
        }
        _ => s * (1.0 + m / 1024.0) * 2f32.powi(e - 15),
    }
}

/// Decode RGBA16F bytes.
pub fn decode_f16_rgba(data: &[u8]) -> Vec<[f32; 4]> {
    data.chunks_exact(8)
        .map(|c| {
            let v = |i: usize| f16_to_f32(u16::from_le_bytes([c[i], c[i + 1]]));
            [v(0), v(2), v(4), v(6)]
        })
        .collect()
}

/// A preview tone map for linear frames: Reinhard, then sRGB.
pub(crate) fn tonemap_preview(p: [f32; 4]) -> [u8; 4] {
    let t = |c: f32| {
        let c = if c.is_finite() { c.max(0.0) } else { 0.0 };
        (crate::reference::metrics::srgb_encode(c / (1.0 + c)) * 255.0 + 0.5) as u8
    };
    [t(p[0]), t(p[1]), t(p[2]), 255]
}

/// The first adapter wgpu finds on the backends Bevy would use, as "name (backend)", or an
/// error line if there is none (e.g. no Vulkan driver: install `mesa-vulkan-drivers`).
pub fn find_adapter() -> Result<String, String> {
    first_adapter()
        .map(|a| {
            let i = a.get_info();
            format!("{} ({:?})", i.name, i.backend)
        })
        .ok_or_else(|| {
            "no GPU adapter found (no Vulkan driver? on Debian/Ubuntu install mesa-vulkan-drivers)"
                .to_string()
        })
}

/// The maxima ([`CausticsLimits`]) of the adapter [`find_adapter`] names: Bevy requests its
/// device at the adapter's own limits, so a job that passes [`check_job`](super::check_job) with these fits.
pub fn adapter_limits() -> Result<CausticsLimits, String> {
    first_adapter()
        .map(|a| CausticsLimits::new(&a.limits()))
        .ok_or_else(|| "no GPU adapter found".to_string())
}

/// The first adapter wgpu finds on the backends Bevy would use.
fn first_adapter() -> Option<wgpu::Adapter> {
    let instance = wgpu::Instance::default();
    bevy::tasks::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .into_iter()
        .next()
}

/// On a headless Linux machine without `XDG_RUNTIME_DIR`, the Wayland client library that the
/// Vulkan loader's WSI pulls in prints "error: XDG_RUNTIME_DIR is invalid" several times,
/// which drowns the renderer's own one-line errors. Point it at a private directory.
///
/// Call it first thing in `main`, before any thread exists (it sets an environment variable).
pub fn quiet_headless_environment() {
    #[cfg(target_os = "linux")]
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = std::env::temp_dir().join("bevy_caustics_runtime");
        if std::fs::create_dir_all(&dir).is_ok() {
            use std::os::unix::fs::PermissionsExt;
            let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
            // SAFETY: documented precondition: called before any other thread is spawned,
            // so no other thread reads the environment concurrently.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}
