//! Once warm, a step allocates nothing: a counting allocator watches a swarm with retinas,
//! IR and ambient sensors, collisions and the regatta controller step, on one thread and on
//! two. (Records that grow with events — a robot's visit sequence, its table of obstacles
//! touched — start with room and allocate only when they outgrow it.)

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use regatta_runtime::sim::Simulation;
use regatta_tests::compile_text;

/// Counts allocations while `COUNTING` is on (from any thread).
struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

// SAFETY: every call is forwarded to the system allocator unchanged.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A crowd with retinas packed tight enough to touch, with lamps to visit.
fn crowd() -> String {
    let mut text = String::from(
        "#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem \"NUE\" basicTimeStep 32 }\n\
         DirectionalLight { direction 0.3 -1 0.2 intensity 0.5 }\nArena { size 0.6 0.6 }\n\
         Buoy { translation 0 0 0 irReflectance 1 }\nBuoy { translation 0.2 0 -0.2 }\n",
    );
    for i in 0..40 {
        let (x, z) = (-0.26 + 0.075 * (i % 8) as f64, -0.26 + 0.1 * (i / 8) as f64);
        text += &format!(
            "Khepera {{ translation {x} 0 {z} rotation 0 1 0 {} name \"k{i}\" controller \"regatta\" \
             turret PanoramicTurret {{ lambda 5 }} }}\n",
            i as f64 * 1.3
        );
    }
    text
}

#[test]
fn a_warm_step_allocates_nothing() {
    let compiled = compile_text(&crowd());
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut simulation = Simulation::new(&compiled, None).unwrap();
            simulation.sense_everything();
            // Warm: every buffer has grown to its size (contacts and visits included).
            simulation.run(500);
            ALLOCATIONS.store(0, Ordering::SeqCst);
            COUNTING.store(true, Ordering::SeqCst);
            simulation.run(200);
            COUNTING.store(false, Ordering::SeqCst);
            let touching = simulation
                .robots
                .iter()
                .filter(|r| r.contacts.events > 0)
                .count();
            assert!(touching > 0, "the crowd touches");
            assert_eq!(
                ALLOCATIONS.load(Ordering::SeqCst),
                0,
                "allocations in 200 warm steps on {threads} thread(s)"
            );
        });
    }
}
