//! One triangle into the buffers: clipped at the near plane, projected, filled span by span
//! with a consistent tie rule (a pixel centre on an edge shared by two triangles is drawn
//! once), its depth interpolated perspective-correctly and written with the triangle's
//! coverage id; its [`Paint`] colours the pixels it keeps once the frame is drawn.

use glam::{DVec2, DVec3};

/// A triangle corner in camera coordinates with its shaded linear colour.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Corner {
    pub position: DVec3,
    pub color: [f64; 3],
    /// The world normal, for triangles shaded per pixel.
    pub normal: DVec3,
}

/// How a drawn triangle's pixels get their colour once the frame's depth test is settled
/// (deferred: only the pixels that stay visible are coloured).
#[derive(Clone, Copy, Debug)]
pub(super) enum Paint {
    /// One colour for every pixel (corners that agree, no shadow edge).
    Flat { bytes: [u8; 3], linear: [f32; 3] },
    /// Gouraud: the corners' colours interpolated perspective-correctly.
    Smooth { w: Plane, color: [Plane; 3] },
    /// Shaded per pixel (a shadow's edge crosses the triangle): the interpolated world normal
    /// and the pixel's depth, with this material and colour override.
    Exact {
        w: Plane,
        normal: [Plane; 3],
        material: usize,
        color: Option<[f64; 3]>,
    },
}

/// Per-pixel shading for a triangle: its material and its first corner's colour override.
pub(super) type PerPixel = Option<(usize, Option<[f64; 3]>)>;

/// The depth and coverage buffers the triangles are drawn into, and what colours them.
pub(super) struct Buffers<'a> {
    pub depth: &'a mut [f32],
    /// Per pixel, the covering triangle's index in `paints` plus one (0: the background).
    pub ids: &'a mut [u32],
    pub paints: &'a mut Vec<Paint>,
    /// Column centres, `column + 0.5`.
    pub centres: &'a [f64],
}

/// The image the triangles land on.
pub(super) struct Screen<'a> {
    pub width: usize,
    pub height: usize,
    /// The clipping plane's depth (camera x).
    pub near_x: f64,
    pub near: f64,
    pub far: f64,
    pub tan_h: f64,
    pub tan_v: f64,
    pub lengths: &'a [f64],
    /// The smallest and the largest of `lengths`.
    pub shortest: f64,
    pub longest: f64,
}

/// A linear channel value to 0…255, rounded half up, clamped (NaN: 0), as the ray-cast
/// camera converts it; `as` truncates, which is the floor for the non-negative values here.
pub(super) fn to_byte(value: f64) -> u8 {
    (value.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// Clips against the near plane and fills what is left.
pub(super) fn draw(
    screen: &Screen,
    corners: [Corner; 3],
    buffers: &mut Buffers,
    per_pixel: PerPixel,
) {
    if corners
        .iter()
        .any(|c| !c.position.is_finite() || c.color.iter().any(|v| !v.is_finite()))
    {
        return;
    }
    let inside = corners.map(|c| c.position.x >= screen.near_x);
    let mut polygon = [Corner::default(); 4];
    let mut count = 0;
    if inside.iter().all(|&i| i) {
        polygon[..3].copy_from_slice(&corners);
        count = 3;
    } else {
        // Sutherland–Hodgman against x = near_x: at most four corners remain.
        for k in 0..3 {
            let (a, b) = (corners[k], corners[(k + 1) % 3]);
            let (ia, ib) = (inside[k], inside[(k + 1) % 3]);
            if ia {
                polygon[count] = a;
                count += 1;
            }
            if ia != ib {
                let t = (screen.near_x - a.position.x) / (b.position.x - a.position.x);
                let mut color = [0.0; 3];
                for (k, c) in color.iter_mut().enumerate() {
                    *c = a.color[k] + (b.color[k] - a.color[k]) * t;
                }
                let mut position = a.position + (b.position - a.position) * t;
                position.x = screen.near_x;
                let normal = a.normal + (b.normal - a.normal) * t;
                polygon[count] = Corner {
                    position,
                    color,
                    normal,
                };
                count += 1;
            }
        }
    }
    for k in 1..count.saturating_sub(1) {
        fill(
            screen,
            [polygon[0], polygon[k], polygon[k + 1]],
            buffers,
            per_pixel,
        );
    }
}

/// A plane over the screen: `value(p) = a·x + b·y + c`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plane {
    a: f64,
    b: f64,
    c: f64,
}

impl Plane {
    fn through(p: [DVec2; 3], v: [f64; 3], area: f64) -> Plane {
        let (d1, d2) = (p[1] - p[0], p[2] - p[0]);
        let (v1, v2) = (v[1] - v[0], v[2] - v[0]);
        let a = (v1 * d2.y - v2 * d1.y) / area;
        let b = (v2 * d1.x - v1 * d2.x) / area;
        Plane {
            a,
            b,
            c: v[0] - a * p[0].x - b * p[0].y,
        }
    }

    pub(super) fn at(&self, x: f64, y: f64) -> f64 {
        self.a * x + self.b * y + self.c
    }
}

/// An edge's inside test `dx·(py − ay) − dy·(px − ax) ≥ 0`, with the tie rule.
#[derive(Clone, Copy)]
struct Edge {
    origin: DVec2,
    d: DVec2,
    /// Whether a pixel centre exactly on it is inside: one of the two orientations of an
    /// edge, so that two triangles sharing it never both draw (nor both skip) the pixel.
    ties: bool,
}

impl Edge {
    fn new(a: DVec2, b: DVec2) -> Edge {
        let d = b - a;
        Edge {
            origin: a,
            d,
            ties: d.y > 0.0 || (d.y == 0.0 && d.x > 0.0),
        }
    }

    fn value(&self, x: f64, y: f64) -> f64 {
        self.d.x * (y - self.origin.y) - self.d.y * (x - self.origin.x)
    }

    fn inside(&self, x: f64, y: f64) -> bool {
        let e = self.value(x, y);
        e > 0.0 || (e == 0.0 && self.ties)
    }
}

fn fill(screen: &Screen, corners: [Corner; 3], buffers: &mut Buffers, per_pixel: PerPixel) {
    let (w, h) = (screen.width as f64, screen.height as f64);
    let project = |q: DVec3| {
        DVec2::new(
            (q.z / q.x / screen.tan_h + 1.0) * w / 2.0,
            (1.0 - q.y / q.x / screen.tan_v) * h / 2.0,
        )
    };
    let mut p = corners.map(|c| project(c.position));
    let mut c = corners;
    let mut area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
    if !(area.is_finite() && area.abs() > 1e-12) {
        return;
    }
    // One orientation for every triangle: the edges' inside is then always the left.
    if area < 0.0 {
        p.swap(1, 2);
        c.swap(1, 2);
        area = -area;
    }
    let inverse_depth = c.map(|c| 1.0 / c.position.x);
    let w_plane = Plane::through(p, inverse_depth, area);
    let paint = match per_pixel {
        Some((material, color)) => Paint::Exact {
            w: w_plane,
            normal: std::array::from_fn(|k| {
                Plane::through(
                    p,
                    [0, 1, 2].map(|i| c[i].normal[k] * inverse_depth[i]),
                    area,
                )
            }),
            material,
            color,
        },
        None if c[0].color == c[1].color && c[1].color == c[2].color => Paint::Flat {
            bytes: c[0].color.map(to_byte),
            linear: c[0].color.map(|v| v as f32),
        },
        None => Paint::Smooth {
            w: w_plane,
            color: std::array::from_fn(|k| {
                Plane::through(p, [0, 1, 2].map(|i| c[i].color[k] * inverse_depth[i]), area)
            }),
        },
    };
    // With the area positive, each edge's value is positive on the triangle's side.
    let edges = [
        Edge::new(p[0], p[1]),
        Edge::new(p[1], p[2]),
        Edge::new(p[2], p[0]),
    ];
    let min_y = p.iter().fold(f64::INFINITY, |m, q| m.min(q.y));
    let max_y = p.iter().fold(f64::NEG_INFINITY, |m, q| m.max(q.y));
    let first_row = (min_y - 0.5).ceil().clamp(0.0, h) as usize;
    let last_row = (max_y - 0.5).floor().clamp(-1.0, h - 1.0);
    if last_row < 0.0 {
        return;
    }
    let last_row = last_row as usize;
    let mut id = 0;
    for row in first_row..=last_row.min(screen.height - 1) {
        let y = row as f64 + 0.5;
        // Each edge bounds x on one side; the span is their intersection, widened by a pixel
        // and then trimmed with the exact test, so rounding never adds or drops a pixel.
        let (mut lo, mut hi) = (0.0f64, w);
        let mut empty = false;
        for e in &edges {
            let slope = -e.d.y;
            let offset = e.d.x * (y - e.origin.y) + e.d.y * e.origin.x;
            if slope > 0.0 {
                lo = lo.max(-offset / slope);
            } else if slope < 0.0 {
                hi = hi.min(-offset / slope);
            } else if offset < 0.0 || (offset == 0.0 && !e.ties) {
                empty = true;
            }
        }
        // A NaN bound (a degenerate edge) leaves the row empty too.
        if empty || lo.is_nan() || hi.is_nan() || lo > hi + 1.0 {
            continue;
        }
        let mut start = ((lo - 1.5).floor().max(0.0)) as usize;
        let mut end = ((hi + 0.5).ceil().min(w - 1.0)).max(-1.0) as isize;
        let inside = |column: usize| {
            let x = column as f64 + 0.5;
            edges.iter().all(|e| e.inside(x, y))
        };
        while (start as isize) <= end && !inside(start) {
            start += 1;
        }
        while end >= start as isize && !inside(end as usize) {
            end -= 1;
        }
        if end < start as isize {
            continue;
        }
        if id == 0 {
            buffers.paints.push(paint);
            id = buffers.paints.len() as u32;
        }
        let base = row * screen.width;
        let (first, past) = (base + start, base + end as usize + 1);
        let (depth, ids) = (
            &mut buffers.depth[first..past],
            &mut buffers.ids[first..past],
        );
        let centres = &buffers.centres[start..=end as usize];
        let (low, high) = span_bounds(w_plane, y, centres);
        // Rounded products are monotonic, so `near·wv` and `far·wv` stay on the safe side of
        // every pixel's length when they do at the bounds (NaN anywhere: the full test).
        let near_safe = screen.near * high < screen.shortest;
        // (`far` not positive, NaN included: no far limit, as `span` reads it.)
        let unlimited = screen.far.is_nan() || screen.far <= 0.0;
        let far_safe = unlimited || screen.far * low >= screen.longest;
        if !(near_safe && far_safe) {
            span(
                depth,
                ids,
                &screen.lengths[first..past],
                centres,
                w_plane,
                y,
                screen.near,
                screen.far,
                id,
            );
        } else if low > 0.0 {
            span_unclipped::<true>(depth, ids, centres, w_plane, y, id);
        } else {
            span_unclipped::<false>(depth, ids, centres, w_plane, y, id);
        }
    }
}

/// Bounds of the plane's computed values over a span (`centres`, on row centre `y`): where
/// they show that no pixel can be clipped by near…far, the span is drawn without reading the
/// pixels' ray lengths, and where they are positive, without testing for it.
///
/// Along the row the plane's exact value is linear, so it lies between its values at the
/// span's ends; each pixel's computed value is within a few roundings of it, and `slack`
/// bounds those (with room for the ends' own).
fn span_bounds(w_plane: Plane, y: f64, centres: &[f64]) -> (f64, f64) {
    let (Some(&first), Some(&last)) = (centres.first(), centres.last()) else {
        return (f64::NAN, f64::NAN);
    };
    let (a, by, c) = (w_plane.a, w_plane.b * y, w_plane.c);
    let (w0, w1) = (a * first + by + c, a * last + by + c);
    let slack = 8.0 * f64::EPSILON * (a.abs() * first.abs().max(last.abs()) + by.abs() + c.abs());
    (w0.min(w1) - slack, w0.max(w1) + slack)
}

/// [`span`] where no pixel is nearer than `near` or farther than `far`: the same depth test
/// without them (and, when `POSITIVE`, every pixel's value is known to be positive).
#[inline(never)]
fn span_unclipped<const POSITIVE: bool>(
    depth: &mut [f32],
    ids: &mut [u32],
    centres: &[f64],
    w_plane: Plane,
    y: f64,
    id: u32,
) {
    let n = depth.len();
    let (ids, centres) = (&mut ids[..n], &centres[..n]);
    let (a, by, c) = (w_plane.a, w_plane.b * y, w_plane.c);
    const LANES: usize = 4;
    let mut d = depth.chunks_exact_mut(LANES);
    let mut i = ids.chunks_exact_mut(LANES);
    let mut x = centres.chunks_exact(LANES);
    for ((d, i), x) in (&mut d).zip(&mut i).zip(&mut x) {
        let wv: [f64; LANES] = std::array::from_fn(|j| a * x[j] + by + c);
        let stored = wv.map(|v| v as f32);
        let hidden: [bool; LANES] =
            std::array::from_fn(|j| (stored[j] <= d[j]) | (!POSITIVE & (wv[j] <= 0.0)));
        let keep = hidden.map(|h| u32::from(h).wrapping_neg());
        for j in 0..LANES {
            d[j] = f32::from_bits((d[j].to_bits() & keep[j]) | (stored[j].to_bits() & !keep[j]));
            i[j] = (i[j] & keep[j]) | (id & !keep[j]);
        }
    }
    for ((d, i), &x) in d
        .into_remainder()
        .iter_mut()
        .zip(i.into_remainder())
        .zip(x.remainder())
    {
        let wv = a * x + by + c;
        let stored = wv as f32;
        if !((stored <= *d) | (!POSITIVE & (wv <= 0.0))) {
            *d = stored;
            *i = id;
        }
    }
}

/// The depth test along one row's span: where the triangle is nearer than what is drawn and
/// within the camera's near…far (as the ray caster clips: distance along the pixel's ray),
/// its depth and `id` replace what was there. Branch-free, so that it vectorises.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn span(
    depth: &mut [f32],
    ids: &mut [u32],
    lengths: &[f64],
    centres: &[f64],
    w_plane: Plane,
    y: f64,
    near: f64,
    far: f64,
    id: u32,
) {
    let n = depth.len();
    let (ids, lengths, centres) = (&mut ids[..n], &lengths[..n], &centres[..n]);
    // `Plane::at`'s sum, in its order: (a·x + b·y) + c.
    let (a, by, c) = (w_plane.a, w_plane.b * y, w_plane.c);
    // No far limit: an infinite one hides the same pixels (those with `wv > 0`: none; the
    // others are hidden anyway, and NaN compares false either way).
    let far = if far > 0.0 { far } else { f64::INFINITY };
    let test = |depth: &mut f32, ids: &mut u32, length: f64, x: f64| {
        let wv = a * x + by + c;
        let stored = wv as f32;
        let hidden = (stored <= *depth) | (wv <= 0.0) | (length < near * wv) | (length > far * wv);
        *depth = if hidden { *depth } else { stored };
        *ids = if hidden { *ids } else { id };
    };
    // Four pixels at a time (the same tests: each pixel is independent of the others).
    const LANES: usize = 4;
    let mut d = depth.chunks_exact_mut(LANES);
    let mut i = ids.chunks_exact_mut(LANES);
    let mut l = lengths.chunks_exact(LANES);
    let mut x = centres.chunks_exact(LANES);
    for (((d, i), l), x) in (&mut d).zip(&mut i).zip(&mut l).zip(&mut x) {
        let wv: [f64; LANES] = std::array::from_fn(|j| a * x[j] + by + c);
        let stored = wv.map(|v| v as f32);
        let hidden: [bool; LANES] = std::array::from_fn(|j| {
            (stored[j] <= d[j]) | (wv[j] <= 0.0) | (l[j] < near * wv[j]) | (l[j] > far * wv[j])
        });
        // Selected by masks rather than branches, so that the four go together.
        let keep = hidden.map(|h| u32::from(h).wrapping_neg());
        for j in 0..LANES {
            d[j] = f32::from_bits((d[j].to_bits() & keep[j]) | (stored[j].to_bits() & !keep[j]));
            i[j] = (i[j] & keep[j]) | (id & !keep[j]);
        }
    }
    for (((d, i), &l), &x) in d
        .into_remainder()
        .iter_mut()
        .zip(i.into_remainder())
        .zip(l.remainder())
        .zip(x.remainder())
    {
        test(d, i, l, x);
    }
}
