//! The media-interface rules of caustics volumes (seed 000, section 3.3): when a photon that
//! hit a transmissive surface in `G_near` really crosses a medium boundary.

use glam::Vec3;

/// What a transmissive hit means for a photon (seed 000 section 3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MediaInterface {
    /// Air to dielectric: refract into the denser medium (`P_med` becomes true).
    Enter,
    /// Dielectric to air: refract out (`P_med` becomes false).
    Exit,
    /// Not an interface for this photon: it stays in its medium and keeps marching.
    Ignore,
}

/// The rule of seed 000 section 3.3, written once:
///
/// 1. The hit is only "at a media interface" when the photon lies between the `G_near` and
///    `G_far` depths (`between_near_far`); otherwise it may pass behind the object.
/// 2. `P_med` false (in air) and the surface normal in the hemisphere opposite to the photon
///    direction (`n · d < 0`): entering the denser medium.
/// 3. `P_med` true (inside) and the normal in the same hemisphere as the direction
///    (`n · d > 0`): exiting it.
/// 4. Otherwise "the interface is ignored and the photon is assumed to remain in the original
///    medium". A direction exactly in the surface (`n · d = 0`, a grazing photon) is in
///    neither hemisphere and is ignored; non-finite inputs are ignored too.
pub fn media_interface(
    p_med: bool,
    dir: Vec3,
    normal: Vec3,
    between_near_far: bool,
) -> MediaInterface {
    let c = normal.dot(dir);
    if !between_near_far || !c.is_finite() {
        return MediaInterface::Ignore;
    }
    match (p_med, c) {
        (false, c) if c < 0.0 => MediaInterface::Enter,
        (true, c) if c > 0.0 => MediaInterface::Exit,
        _ => MediaInterface::Ignore,
    }
}
