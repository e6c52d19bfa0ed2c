//! Footprint geometry as one eye sees it: the upright objects placed in the world, each
//! object's azimuth interval and silhouette corners, the footprint relative to the eye with
//! its horizontal ray crossing, and which static objects may hide a rectangle's corner.

use glam::DVec2;

use super::photodiode::{larger, smaller};
use crate::compile::graph::{RenderGraph, Shape};
use crate::geometry::Footprint;

/// An upright object placed in the world.
#[derive(Clone, Copy, Debug)]
pub(super) struct Upright {
    pub(super) primitive: usize,
    pub(super) footprint: Footprint,
    pub(super) y0: f64,
    pub(super) y1: f64,
    pub(super) side: bool,
    pub(super) top: bool,
    pub(super) bottom: bool,
}

pub(super) fn upright_of(
    graph: &RenderGraph,
    primitive: usize,
    frame: &crate::geometry::Frame,
) -> Option<Upright> {
    let p = &graph.primitives[primitive];
    let (footprint, half_height) = p.shape.footprint(frame)?;
    let (side, top, bottom) = match &p.shape {
        Shape::Cylinder {
            side, top, bottom, ..
        } => (*side, *top, *bottom),
        _ => (true, true, true),
    };
    let center = frame.translation;
    Some(Upright {
        primitive,
        footprint,
        y0: center.y - half_height,
        y1: center.y + half_height,
        side,
        top,
        bottom,
    })
}

/// Wraps an angle to (−π, π].
#[inline]
pub(super) fn wrap(angle: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    // Within a turn the remainder is the angle itself: skip the division.
    let mut a = if angle.abs() < two_pi {
        angle
    } else {
        angle % two_pi
    };
    if a <= -std::f64::consts::PI {
        a += two_pi;
    } else if a > std::f64::consts::PI {
        a -= two_pi;
    }
    a
}

/// A static object that may hide a static rectangle's corner: the corner lies in (or on) its
/// footprint and its height range holds the rectangle's. Whether it does hide it depends on
/// the eye (see [`ColumnScene::edge_hidden`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Hider {
    /// The rectangle's corner (see [`RECT_CORNERS`]).
    pub(super) corner: u8,
    /// The hiding object's index.
    pub(super) object: u16,
}

/// A silhouette edge that waits for the hidden-edge test.
#[derive(Clone, Copy, Debug)]
pub(super) struct PendingEdge {
    pub(super) angle: f64,
    /// The hidden object's index in the look, and among the static objects.
    pub(super) object: u32,
    pub(super) order: u32,
    pub(super) corner: u8,
    /// From the eye to the corner, in (x, z).
    pub(super) to_corner: DVec2,
}

/// For each static object, the hiders of its corners.
pub(super) fn corner_hiders(statics: &[Upright]) -> Vec<Vec<Hider>> {
    statics
        .iter()
        .enumerate()
        .map(|(index, object)| {
            let mut hiders = Vec::new();
            // Objects are named by u16 indices in a look.
            if index > u16::MAX as usize {
                return hiders;
            }
            let (_, reach) = object.footprint.bounding_circle();
            for corner in 0..RECT_CORNERS.len() {
                let Some(point) = corner_of(&object.footprint, corner) else {
                    break;
                };
                // Touching within rounding of the coordinates (walls built edge to edge).
                let tolerance = 1e-9 * (1.0 + point.length() + reach);
                for (other, hider) in statics.iter().enumerate().take(u16::MAX as usize + 1) {
                    if other != index
                        && hider.side
                        && hider.y0 <= object.y0
                        && hider.y1 >= object.y1
                        && hider.footprint.distance(point) <= tolerance
                    {
                        hiders.push(Hider {
                            corner: corner as u8,
                            object: other as u16,
                        });
                    }
                }
            }
            hiders
        })
        .collect()
}

/// The corners of a rectangular footprint, in the order [`Interval::corners`] counts them.
pub(super) const RECT_CORNERS: [(f64, f64); 4] =
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];

/// Corner `k` of a rectangular footprint (see [`RECT_CORNERS`]).
#[inline]
pub(super) fn rect_corner(
    center: DVec2,
    u: DVec2,
    v: DVec2,
    half_u: f64,
    half_v: f64,
    k: usize,
) -> DVec2 {
    let (su, sv) = RECT_CORNERS[k];
    center + u * (su * half_u) + v * (sv * half_v)
}

/// Corner `k` of a footprint (see [`RECT_CORNERS`]): a circle has none.
pub(super) fn corner_of(footprint: &Footprint, k: usize) -> Option<DVec2> {
    match *footprint {
        Footprint::Rect {
            center,
            u,
            v,
            half_u,
            half_v,
        } => Some(rect_corner(center, u, v, half_u, half_v, k)),
        Footprint::Circle { .. } => None,
    }
}

/// Whether `point` lies strictly inside `footprint`.
pub(super) fn surrounds(footprint: &Footprint, point: DVec2) -> bool {
    match *footprint {
        Footprint::Rect {
            center,
            u,
            v,
            half_u,
            half_v,
        } => {
            let offset = point - center;
            offset.dot(u).abs() < half_u && offset.dot(v).abs() < half_v
        }
        Footprint::Circle { center, radius } => center.distance_squared(point) < radius * radius,
    }
}

/// An object's azimuth interval relative to the viewer's heading.
#[derive(Clone, Copy, Debug)]
pub(super) struct Interval {
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// For a rectangle, the corners whose vertical edges are the silhouette at `lo` and `hi`.
    pub(super) corners: Option<(u8, u8)>,
}

/// An object's azimuth interval relative to `heading`, or `None` when it surrounds the eye.
///
/// `crowd`: a silhouette's angles (round or rectangular) by the polynomial arctangent
/// impostors use (within 2e-8 rad, a millionth of a photodiode; no branch on the octant)
/// instead of the C library's `atan2`, `atan` and `asin`, whose branches a crowd's look
/// mispredicts. Exact rendering keeps them.
pub(super) fn azimuth_interval(
    object: &Upright,
    eye: DVec2,
    heading: f64,
    crowd: bool,
) -> Option<Interval> {
    match object.footprint {
        Footprint::Circle { center, radius } => {
            let offset = center - eye;
            let distance = offset.length();
            if distance <= radius {
                return None;
            }
            let (middle, half) = if crowd {
                let sine = (radius / distance).min(1.0);
                (
                    super::impostor::atan2(-offset.y, offset.x),
                    super::impostor::atan2(sine, (1.0 - sine * sine).sqrt()),
                )
            } else {
                (
                    libm::atan2(-offset.y, offset.x),
                    libm::asin((radius / distance).min(1.0)),
                )
            };
            let middle = wrap(middle - heading);
            Some(Interval {
                lo: middle - half,
                hi: middle + half,
                corners: None,
            })
        }
        Footprint::Rect {
            center,
            u,
            v,
            half_u,
            half_v,
        } => {
            let offset = center - eye;
            let (pu, pv) = (-offset.dot(u), -offset.dot(v));
            if pu.abs() <= half_u && pv.abs() <= half_v {
                return None;
            }
            let middle = if crowd {
                super::impostor::atan2(-offset.y, offset.x)
            } else {
                libm::atan2(-offset.y, offset.x)
            };
            // Corners as (x, −z) so that angles grow counter-clockwise; relative to the middle
            // direction m an angle is atan(cross/dot) while every corner is in front of it,
            // so only the two extreme corners need a transcendental.
            let m = DVec2::new(offset.x, -offset.y);
            let mut ratios = [0.0; 4];
            let mut crosses = [(0.0, 0.0); 4];
            let mut in_front = true;
            for ((k, ratio), cross) in ratios.iter_mut().enumerate().zip(&mut crosses) {
                let corner = rect_corner(center, u, v, half_u, half_v, k) - eye;
                let c = DVec2::new(corner.x, -corner.y);
                let dot = m.dot(c);
                in_front &= dot > 0.0;
                *cross = (m.perp_dot(c), dot);
                *ratio = cross.0 / dot;
            }
            let mut angles = [0.0; 4];
            let extreme = if in_front {
                ratios
            } else {
                for (k, angle) in angles.iter_mut().enumerate() {
                    let corner = rect_corner(center, u, v, half_u, half_v, k) - eye;
                    let angle_of = if crowd {
                        super::impostor::atan2(-corner.y, corner.x)
                    } else {
                        libm::atan2(-corner.y, corner.x)
                    };
                    *angle = wrap(angle_of - middle);
                }
                angles
            };
            // The first of equal extremes, as a fold keeps it.
            let (mut lo_k, mut hi_k) = (0, 0);
            for k in 1..4 {
                if extreme[k] < extreme[lo_k] {
                    lo_k = k;
                }
                if extreme[k] > extreme[hi_k] {
                    hi_k = k;
                }
            }
            let (lo, hi) = if in_front && crowd {
                // atan(cross/dot) with dot > 0: the polynomial takes both, no division first.
                let angle = |(cross, dot): (f64, f64)| super::impostor::atan2(cross, dot);
                (angle(crosses[lo_k]), angle(crosses[hi_k]))
            } else if in_front {
                (libm::atan(ratios[lo_k]), libm::atan(ratios[hi_k]))
            } else {
                (angles[lo_k], angles[hi_k])
            };
            let middle = wrap(middle - heading);
            Some(Interval {
                lo: middle + lo,
                hi: middle + hi,
                corners: Some((lo_k as u8, hi_k as u8)),
            })
        }
    }
}

/// A footprint relative to the eye, with what does not depend on the direction precomputed.
#[derive(Clone, Copy, Debug)]
pub(super) enum Relative {
    Circle {
        oc: DVec2,
        c: f64,
        radius: f64,
    },
    Rect {
        pu: f64,
        pv: f64,
        u: DVec2,
        v: DVec2,
        half_u: f64,
        half_v: f64,
        /// u = +x and v = +z (the usual arena): the column's reciprocals serve.
        axis_aligned: bool,
    },
}

impl Relative {
    /// Entry and exit distances of the horizontal ray, with the entry normal; `inverse` holds
    /// the reciprocals of `direction`'s components.
    #[inline(always)]
    pub(super) fn cross(&self, direction: DVec2, inverse: DVec2) -> Option<(f64, f64, DVec2)> {
        match *self {
            Relative::Circle { oc, c, radius, .. } => {
                let b = oc.dot(direction);
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let sq = disc.sqrt();
                let (t0, t1) = (-b - sq, -b + sq);
                if t1 <= 0.0 {
                    return None;
                }
                Some((larger(t0, 0.0), t1, (oc + direction * t0) / radius))
            }
            Relative::Rect {
                pu,
                pv,
                u,
                v,
                half_u,
                half_v,
                axis_aligned,
            } => {
                let (t_in, t_out, (axis, sign)) = if axis_aligned {
                    // Axis-aligned (the usual arena): the column's shared reciprocals.
                    if direction.x.abs() >= 1e-300 && direction.y.abs() >= 1e-300 {
                        axis_slabs(pu, pv, direction, inverse, half_u, half_v)?
                    } else {
                        crate::geometry::rect_slabs_inverse(
                            pu,
                            pv,
                            (direction.x, inverse.x),
                            (direction.y, inverse.y),
                            half_u,
                            half_v,
                        )?
                    }
                } else {
                    crate::geometry::rect_slabs(
                        pu,
                        pv,
                        direction.dot(u),
                        direction.dot(v),
                        half_u,
                        half_v,
                    )?
                };
                if t_out <= 0.0 {
                    return None;
                }
                let normal = if axis == 0 { u * sign } else { v * sign };
                Some((larger(t_in, 0.0), t_out, normal))
            }
        }
    }

    /// Where the segment from the eye to `eye + to` enters the footprint, as a fraction of
    /// `to` (negative when the eye is inside), or `None` if the line misses it.
    pub(super) fn entry(&self, to: DVec2) -> Option<f64> {
        match *self {
            Relative::Circle { oc, c, .. } => {
                let (a, b) = (to.length_squared(), oc.dot(to));
                let disc = b * b - a * c;
                (disc >= 0.0 && a > 0.0).then(|| (-b - disc.sqrt()) / a)
            }
            Relative::Rect {
                pu,
                pv,
                u,
                v,
                half_u,
                half_v,
                ..
            } => crate::geometry::rect_slabs(pu, pv, to.dot(u), to.dot(v), half_u, half_v)
                .map(|(t_in, _, _)| t_in),
        }
    }

    /// The outward normal where the ray leaves, at distance `t`.
    pub(super) fn exit_normal(&self, direction: DVec2, t: f64) -> DVec2 {
        match *self {
            Relative::Circle { oc, radius, .. } => (oc + direction * t) / radius,
            Relative::Rect {
                pu,
                pv,
                u,
                v,
                half_u,
                half_v,
                ..
            } => {
                let (qu, qv) = (
                    (pu + direction.dot(u) * t) / half_u,
                    (pv + direction.dot(v) * t) / half_v,
                );
                if qu.abs() >= qv.abs() {
                    u * qu.signum()
                } else {
                    v * qv.signum()
                }
            }
        }
    }
}

/// [`crate::geometry::rect_slabs_inverse`] for a direction with no zero component, in
/// straight-line code (the same operations, so the same results).
#[inline(always)]
pub(super) fn axis_slabs(
    pu: f64,
    pv: f64,
    direction: DVec2,
    inverse: DVec2,
    half_u: f64,
    half_v: f64,
) -> Option<(f64, f64, (usize, f64))> {
    let ordered = |a: f64, b: f64| if a < b { (a, b) } else { (b, a) };
    let (near_u, far_u) = ordered((-half_u - pu) * inverse.x, (half_u - pu) * inverse.x);
    let (near_v, far_v) = ordered((-half_v - pv) * inverse.y, (half_v - pv) * inverse.y);
    let facing = |d: f64| if d > 0.0 { -1.0 } else { 1.0 };
    let mut t_in = f64::NEG_INFINITY;
    let mut face = (0, 0.0);
    if near_u > t_in {
        t_in = near_u;
        face = (0, facing(direction.x));
    }
    if near_v > t_in {
        t_in = near_v;
        face = (1, facing(direction.y));
    }
    let t_out = smaller(far_u, far_v);
    (t_in <= t_out && t_out >= 0.0).then_some((t_in, t_out, face))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A crowd's look places silhouettes by the polynomial arctangent: round and rectangular
    /// footprints, seen from anywhere outside them and facing any way, get the exact look's
    /// intervals within 1e-7 rad (a fifteen-thousandth of a photodiode) and the same corners.
    #[test]
    fn a_crowds_intervals_are_the_exact_ones_within_a_tenth_of_a_microradian() {
        let mut unit = crate::test_random::unit_stream(41);
        let mut compared = 0;
        for case in 0..20_000 {
            let center = DVec2::new(unit() * 8.0 - 4.0, unit() * 8.0 - 4.0);
            let footprint = if case % 2 == 0 {
                Footprint::Circle {
                    center,
                    radius: 0.01 + unit() * 0.5,
                }
            } else {
                let turn = unit() * std::f64::consts::TAU;
                let u = DVec2::new(libm::cos(turn), libm::sin(turn));
                Footprint::Rect {
                    center,
                    u,
                    v: u.perp(),
                    half_u: 0.005 + unit() * 5.0,
                    half_v: 0.005 + unit() * 0.3,
                }
            };
            let object = Upright {
                primitive: 0,
                footprint,
                y0: 0.0,
                y1: 0.1,
                side: true,
                top: true,
                bottom: false,
            };
            let eye = DVec2::new(unit() * 10.0 - 5.0, unit() * 10.0 - 5.0);
            let heading = unit() * std::f64::consts::TAU - std::f64::consts::PI;
            let exact = azimuth_interval(&object, eye, heading, false);
            let crowd = azimuth_interval(&object, eye, heading, true);
            let (Some(exact), Some(crowd)) = (exact, crowd) else {
                assert!(exact.is_none() && crowd.is_none(), "case {case}");
                continue;
            };
            for (a, b) in [(exact.lo, crowd.lo), (exact.hi, crowd.hi)] {
                assert!(wrap(a - b).abs() < 1e-7, "case {case}: {a} against {b}");
            }
            assert_eq!(exact.corners, crowd.corners, "case {case}");
            compared += 1;
        }
        assert!(compared > 15_000, "{compared} compared");
    }
}
