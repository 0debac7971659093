//! The 2015 baseline: area-weighted dart throwing at the same density. Pool
//! points are independent random draws, so taking them in pool order and
//! keeping each one that does not conflict with an earlier keeper is dart
//! throwing with rejection (random sequential adsorption), maximal with
//! respect to the pool.

use super::disk::DiskSampler;

/// Throws every pool point in turn (`slots` in draw order); keepers become samples.
pub(crate) fn sample_random(disk: &mut DiskSampler<'_>, slots: &[u32]) {
    let mut scratch = Vec::new();
    for &j in slots {
        if disk.should_stop() {
            break;
        }
        if !disk.is_alive(j) {
            continue;
        }
        if disk.conflicts(j) {
            disk.discard(j);
            continue;
        }
        disk.place(j, &mut scratch);
    }
}
