//! No per-frame allocation that grows with the animation length: the live
//! heap after 1000 steps is no larger than after 100 (a counting allocator
//! wraps the system allocator in this test binary).

mod common;

use common::shapes::grid;
use plumage::{Config, MeshInput, Mode, System};
use std::alloc::{GlobalAlloc, Layout, System as Heap};
use std::sync::atomic::{AtomicIsize, Ordering};

struct Counting;

static LIVE: AtomicIsize = AtomicIsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { Heap.alloc(layout) };
        if !p.is_null() {
            LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { Heap.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { Heap.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_add(new_size as isize - layout.size() as isize, Ordering::Relaxed);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
fn the_live_heap_does_not_grow_with_the_number_of_frames() {
    let plate = grid(6.0, 6.0, 24, 24, 0.0, true);
    for mode in [Mode::Incremental, Mode::Legacy, Mode::Rebuild] {
        let cfg = Config { target_feathers: 300, threads: 1, mode, flow_axis: glam::Vec3::X, ..Config::default() };
        let mut sys = System::new(&cfg, &MeshInput::new(&plate.positions, &plate.indices)).unwrap();
        let frame = |k: usize| -> Vec<f32> {
            let t = k as f32 * 0.05;
            plate.positions.chunks(3).flat_map(|p| [p[0], p[1], 0.3 * (p[0] + t).sin()]).collect()
        };
        // Frames repeat with a period of 126 (t wraps every 2π), so every
        // buffer has met its largest frame well before frame 100.
        let mut live_at_100 = 0;
        let mut peak_after_100 = 0;
        for k in 1..=1000 {
            let f = frame(k % 126);
            sys.step(&f).unwrap();
            drop(f);
            let live = LIVE.load(Ordering::Relaxed);
            if k == 100 {
                live_at_100 = live;
            }
            if k > 100 {
                peak_after_100 = peak_after_100.max(live);
            }
        }
        println!("{mode:?}: live heap after frame 100: {live_at_100} B, highest after: {peak_after_100} B");
        assert!(
            peak_after_100 <= live_at_100,
            "{mode:?}: the heap grew from {live_at_100} to {peak_after_100} bytes over 900 frames"
        );
    }
}
