//! Generated worlds for benchmarks and stress tests (not test fixtures: they are built on
//! demand so that nothing large is checked in).

use std::fmt::Write;

/// A world with one IndexedFaceSet of `points` points on a wavy grid, and its quads as
/// triangles: the shape of a scanned terrain or a CAD export.
// A benchmark's input, not a result: the platform's sin and cos may pick the wave (the parser
// has no libm, and its only other readers are timings).
#[allow(clippy::disallowed_methods)]
pub fn mesh_world(points: usize) -> String {
    let side = (points as f64).sqrt().ceil().max(2.0) as usize;
    let mut out = String::with_capacity(points * 40);
    out.push_str("#VRML_SIM R2023b utf8\nWorldInfo {\n  coordinateSystem \"NUE\"\n}\n");
    out.push_str("Shape {\n  appearance Appearance {\n    material Material {\n      diffuseColor 0.6 0.5 0.4\n    }\n  }\n");
    out.push_str("  geometry IndexedFaceSet {\n    coord Coordinate {\n      point [\n");
    // A cheap deterministic wave, printed with 6 significant digits like exporters do.
    for index in 0..side * side {
        let (i, j) = ((index / side) as f64, (index % side) as f64);
        let x = i * 0.001;
        let z = j * 0.001;
        let y = 0.01 * ((i * 0.37).sin() + (j * 0.23).cos());
        let _ = writeln!(out, "        {x:.6} {y:.6} {z:.6},");
    }
    out.push_str("      ]\n    }\n    coordIndex [\n");
    for i in 0..side - 1 {
        for j in 0..side - 1 {
            let a = i * side + j;
            let _ = writeln!(
                out,
                "      {} {} {} -1, {} {} {} -1,",
                a,
                a + side,
                a + 1,
                a + 1,
                a + side,
                a + side + 1
            );
        }
    }
    out.push_str("    ]\n  }\n}\n");
    out
}
