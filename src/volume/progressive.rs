//! Progressive mode and the schedule of a volume's updates (seed 000 section 3.5 and its
//! discussion: "a progressive approach ... where a fraction of the total number of photons is
//! traversed per update, up to some maximum count, to preserve frame rates in weak and low-end
//! devices"; differential updates: "if ... a change occurred in the 5th slab, we would only
//! require to update slab 5 and the projectors").
//!
//! The seeded photons that carry flux form the *trace list*. Without progressive mode an update
//! traces the whole list. With it, each frame traces the next `batch` entries of the list through
//! every slab and projects them; their splats accumulate with the earlier batches', and the
//! splat pass scales flux by `live / traced` ([`progressive_scale`]), so the image is an
//! estimate of the full result at every frame and equals it once the whole list is traced.
//! The list is ordered so that every prefix is spread evenly over the entry face
//! ([`progressive_order`]).

/// What one update runs: slab passes from `first_slab` on (`first_slab == slabs`: none), the
/// photons `trace` (a range of the trace list) through slab 0, and the projector march over the
/// trace-list range `project`. Ranges are `start..end`, half open.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VolumeRun {
    /// First slab to re-run.
    pub first_slab: u32,
    /// Trace-list range entering slab 0 (ignored when `first_slab > 0`).
    pub trace: (u32, u32),
    /// Trace-list range the projectors march; a range starting at 0 clears the earlier hits
    /// and density tiles, any other adds to them.
    pub project: (u32, u32),
    /// Trace-list entries traced once this run is done.
    pub traced_after: u32,
}

impl VolumeRun {
    /// The run starts a new accumulation: every final photon state is cleared first.
    pub fn restarts(&self) -> bool {
        self.first_slab == 0 && self.trace.0 == 0
    }
}

/// Photons per progressive batch, or the whole list: `progressive == 0` (off) or a batch at
/// least as large as the list traces everything at once.
pub fn progressive_batch(progressive: u32, live: u32) -> u32 {
    if progressive == 0 || progressive >= live {
        live
    } else {
        progressive
    }
}

/// The update to run this frame.
///
/// * `change`: the first slab touched by a change not yet run (`Some(slabs)`: only the scene
///   outside the volume changed, so only the projectors re-run; `None`: nothing changed).
/// * `slabs`: the volume's effective slab count; `live`: the trace list's length; `traced`:
///   entries traced in the current accumulation; `progressive`: photons per frame (0: off).
///
/// Rules: without progressive mode a change re-runs from its slab (differential updates) over
/// the whole list. With it, a change inside the volume restarts the accumulation from slab 0
/// (the live lists of later slabs hold only the last batch, so they cannot be reused), a change
/// outside it re-projects everything traced so far together with the next batch, and while
/// nothing changes the next batch runs until the list is exhausted; then nothing runs.
pub fn schedule_run(
    change: Option<u32>,
    slabs: u32,
    live: u32,
    traced: u32,
    progressive: u32,
) -> Option<VolumeRun> {
    let slabs = slabs.max(1);
    let batch = progressive_batch(progressive, live);
    let traced = traced.min(live);
    let progressive = batch < live;
    match change {
        Some(k) if k < slabs && !progressive => Some(VolumeRun {
            first_slab: k,
            trace: (0, live),
            project: (0, live),
            traced_after: live,
        }),
        Some(k) if k < slabs => Some(VolumeRun {
            first_slab: 0,
            trace: (0, batch),
            project: (0, batch),
            traced_after: batch,
        }),
        Some(_) if traced >= live || !progressive => Some(VolumeRun {
            first_slab: slabs,
            trace: (0, 0),
            project: (0, traced),
            traced_after: traced,
        }),
        Some(_) => {
            let end = traced.saturating_add(batch).min(live);
            Some(VolumeRun {
                first_slab: 0,
                trace: (traced, end),
                project: (0, end),
                traced_after: end,
            })
        }
        None if progressive && traced < live => {
            let end = traced.saturating_add(batch).min(live);
            Some(VolumeRun {
                first_slab: 0,
                trace: (traced, end),
                project: (traced, end),
                traced_after: end,
            })
        }
        None => None,
    }
}

/// The factor the splats' flux is multiplied by: `live / traced` (each photon carries its
/// share of the whole list's flux, so a partial accumulation is scaled up to an estimate of the
/// full one), 1 when the list is empty or nothing is traced yet.
pub fn progressive_scale(live: u32, traced: u32) -> f32 {
    if traced == 0 || live == 0 {
        1.0
    } else {
        (live as f64 / traced.min(live) as f64) as f32
    }
}

/// The order in which progressive mode traces the photons `indices` (row-major cells of the
/// entry-face grid): sorted by the golden-ratio sequence `frac(i φ)` of their position in the
/// list (computed exactly in 0.64 fixed point), so that every prefix of the order, and so
/// every batch, is a rank-1 lattice spread evenly over the face rather than a strip of rows.
pub fn progressive_order(indices: &[u32]) -> Vec<u32> {
    const PHI_FRAC: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut keyed: Vec<(u64, u32)> = indices
        .iter()
        .enumerate()
        .map(|(n, &i)| ((n as u64).wrapping_mul(PHI_FRAC), i))
        .collect();
    keyed.sort_unstable_by_key(|k| k.0);
    keyed.into_iter().map(|k| k.1).collect()
}
