//! Integrating a strip: pixels cut at silhouette edges and sampled (or, with a stride, the
//! strip cut into smooth regions, each sampled and modelled piecewise linearly), each column
//! composited front to back over the band, its faces shaded (fast where the frame allows).
//! Each thread keeps its working buffers from update to update.

use glam::{DVec2, DVec3};

use super::super::shade;
use super::angular::Sweep;
use super::impostor::Impostor;
use super::impostor::IMPOSTOR_PIXELS;
use super::kept::{KeptImpostors, Refresh};
use super::photodiode::{
    band_atan, Band, Face, Free, Lit, LitSegments, LitSink, Scratch, Segment, SegmentSink,
    Segments, Shown,
};
use super::scene::{ColumnFrame, ColumnScene};
use super::strip::Strip;
use super::sweep::{self, eye_object, EyeObject, Look, Reach, Rounds, Sector};
use crate::compile::graph::LightKind;
use crate::render::Detail;
use crate::retina::luminance;

mod regions;

/// The region sampler's buffers.
#[derive(Default)]
struct RegionBuffers {
    bounds: Vec<f64>,
    /// One region's samples.
    positions: Vec<f64>,
    values: Vec<f64>,
    /// The objects facing the eye in one region.
    facing: Vec<u32>,
    /// What each of a region's sampled columns shows, for the impostors there, and where
    /// each sample's pieces start.
    profile: Vec<Shown>,
    profile_starts: Vec<usize>,
    /// One impostor's pieces.
    pieces: Vec<EyeObject>,
    /// Per region, the objects facing it as bits ([`facing_masks`]).
    masks: Vec<u64>,
}

/// One thread's working buffers: an update's look, sweep, regions and column scratch. Kept
/// from update to update, so that rendering allocates nothing once warm.
struct Workspace {
    look: Look,
    sweep: Sweep,
    buffers: RegionBuffers,
    scratch: Scratch,
}

thread_local! {
    static WORKSPACE: std::cell::Cell<Option<Box<Workspace>>> = const { std::cell::Cell::new(None) };
}

/// Runs `f` with this thread's workspace (a fresh one if it is in use or not yet made).
fn with_workspace<R>(f: impl FnOnce(&mut Workspace) -> R) -> R {
    let mut workspace = WORKSPACE.with(|w| w.take()).unwrap_or_else(|| {
        Box::new(Workspace {
            look: Look::default(),
            sweep: Sweep::default(),
            buffers: RegionBuffers::default(),
            scratch: Scratch {
                segments: Segments::new(),
                lit: LitSegments::new(),
                free: Free::new(),
            },
        })
    });
    let result = f(&mut workspace);
    WORKSPACE.with(|w| w.set(Some(workspace)));
    result
}

impl ColumnScene<'_> {
    /// Mean linear RGB over each pixel of `strip`, seen from `eye` facing `heading`, for the
    /// frame's own viewer.
    ///
    /// `stride` > 1 saves work where it is safe: in a run of pixels whose windows hold no
    /// silhouette edge the column integrand is smooth, so only every `stride`-th pixel (and
    /// each run's ends) is evaluated and the pixels between are interpolated linearly.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate(
        &self,
        frame: &ColumnFrame,
        eye: DVec3,
        heading: f64,
        strip: &Strip,
        detail: Detail,
        out: &mut [f64],
    ) {
        self.integrate_for(frame, frame.viewer, eye, heading, strip, detail, out)
    }

    /// [`ColumnScene::integrate`] for `viewer` in a frame shared by every viewer of a step.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_for(
        &self,
        frame: &ColumnFrame,
        viewer: Option<usize>,
        eye: DVec3,
        heading: f64,
        strip: &Strip,
        detail: Detail,
        out: &mut [f64],
    ) {
        with_workspace(|workspace| {
            self.integrate_with(
                workspace, frame, viewer, eye, heading, strip, detail, false, None, out,
            )
        })
    }

    /// [`ColumnScene::integrate_for`] with the impostors `kept` from the eye's earlier
    /// updates (`crowdKeepDistance`, `kept.rs`): worked out again only when the eye has moved
    /// farther than its distance. Without a crowd distance, or on a strip sampled pixel by
    /// pixel, the same as [`ColumnScene::integrate_for`].
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_kept(
        &self,
        frame: &ColumnFrame,
        viewer: Option<usize>,
        eye: DVec3,
        heading: f64,
        strip: &Strip,
        detail: Detail,
        kept: &mut KeptImpostors,
        out: &mut [f64],
    ) {
        with_workspace(|workspace| {
            self.integrate_with(
                workspace,
                frame,
                viewer,
                eye,
                heading,
                strip,
                detail,
                false,
                Some(kept),
                out,
            )
        })
    }

    /// [`ColumnScene::integrate_for`] the long way: no part left out, and every object tested
    /// against every region between edges. The reference the sweep is checked against (the
    /// same numbers, bit for bit), at a cost that grows with objects × edges.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_exhaustive(
        &self,
        frame: &ColumnFrame,
        viewer: Option<usize>,
        eye: DVec3,
        heading: f64,
        strip: &Strip,
        detail: Detail,
        out: &mut [f64],
    ) {
        with_workspace(|workspace| {
            self.integrate_with(
                workspace, frame, viewer, eye, heading, strip, detail, true, None, out,
            )
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn integrate_with(
        &self,
        workspace: &mut Workspace,
        frame: &ColumnFrame,
        viewer: Option<usize>,
        eye: DVec3,
        heading: f64,
        strip: &Strip,
        detail: Detail,
        exhaustive: bool,
        kept: Option<&mut KeptImpostors>,
        out: &mut [f64],
    ) {
        let (samples, stride) = (detail.samples, detail.stride);
        let Workspace {
            look,
            sweep,
            buffers,
            scratch,
        } = workspace;
        let samples = samples.max(1);
        let stride = stride.max(1);
        let pixels = strip.centers.len().min(out.len());
        // Parts wholly behind the strip face no photodiode: left out where there are many.
        let turn = frame.turn(viewer, heading);
        let sector = (frame.statics.len() + frame.others.len() > sweep::FEW && !exhaustive)
            .then(|| Sector::new(turn, strip))
            .flatten();
        // Far small static objects become impostors, drawn as boxes over contiguous windows.
        let impostors = detail.crowd_distance.is_finite() && strip.contiguous;
        let mut reach = Reach {
            sector,
            crowd_distance: detail.crowd_distance,
            far_distance: detail.far_distance,
            impostor_width: if impostors {
                IMPOSTOR_PIXELS * strip.width
            } else {
                0.0
            },
            extent: strip.extent().unwrap_or((f64::NEG_INFINITY, f64::INFINITY)),
            out_of_band: if detail.crowd_distance.is_finite() {
                strip.tan_half_band
            } else {
                f64::INFINITY
            },
            rounds: Rounds::Tell,
            turn: Some(turn),
        };
        let band = 2.0 * band_atan(strip.tan_half_band);
        let sky = luminance(self.background(1.0));
        // Below the horizon, the background's ground, or a floor the look draws as one.
        let background_ground = luminance(self.background(-1.0));
        let ground_of = |look: &Look| {
            look.ground_floor
                .and_then(|floor| frame.fast_shade(floor))
                .map_or(background_ground, |fast| fast.up_luminance)
        };
        // Kept impostors, on a strip sampled by regions with impostors: told all around the
        // eye and worked out when stale, else the groups placed last time placed again.
        let mut kept = kept.filter(|_| impostors && stride > 1 && !exhaustive);
        if let Some(kept) = &mut kept {
            let setting = [
                detail.crowd_distance.to_bits(),
                detail.far_distance.to_bits(),
                reach.impostor_width.to_bits(),
                strip.tan_half_band.to_bits(),
            ];
            let stale = kept.stale(&frame.statics, eye, setting);
            if stale {
                reach.rounds = Rounds::TellAround;
                reach.extent = (f64::NEG_INFINITY, f64::INFINITY);
            } else {
                reach.rounds = Rounds::Given;
                look.keep_rounds(kept.near());
            }
            self.look_into(frame, viewer, eye, heading, reach, look);
            if stale {
                let column_band = Band {
                    tan_half: strip.tan_half_band,
                    band,
                    sky,
                    ground: ground_of(look),
                };
                self.keep_impostors(
                    frame,
                    look,
                    setting,
                    kept,
                    Refresh {
                        band: &column_band,
                        facing: &mut buffers.facing,
                        pieces: &mut buffers.pieces,
                        profile: &mut buffers.profile,
                        scratch,
                    },
                );
                // The regions draw none: the kept boxes stand in for them all.
                look.impostor_order.clear();
            }
        } else {
            self.look_into(frame, viewer, eye, heading, reach, look);
        }
        let look = &*look;
        let ground = ground_of(look);
        sweep.start(look, exhaustive);
        if stride > 1 && strip.contiguous {
            self.integrate_regions(
                look,
                sweep,
                frame,
                strip,
                stride,
                band,
                sky,
                ground,
                buffers,
                scratch,
                &mut out[..pixels],
            );
            if let Some(kept) = &kept {
                self.draw_kept(look, heading, kept, strip, &mut out[..pixels]);
            }
            return;
        }
        self.integrate_pixels(
            look,
            sweep,
            frame,
            strip,
            (samples, band, sky, ground),
            buffers,
            scratch,
            &mut out[..pixels],
        );
    }

    /// A strip sampled pixel by pixel (`stride 1`, or windows that are not contiguous): each
    /// window cut at silhouette edges, `samples` columns a piece, then the impostors. Out of
    /// line: the crowd setting samples by regions, and its hot path stays small.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn integrate_pixels(
        &self,
        look: &Look,
        sweep: &mut Sweep,
        frame: &ColumnFrame,
        strip: &Strip,
        (samples, band, sky, ground): (usize, f64, f64, f64),
        buffers: &mut RegionBuffers,
        scratch: &mut Scratch,
        out: &mut [f64],
    ) {
        let pixels = out.len();
        let half = strip.width / 2.0;
        let facing = &mut buffers.facing;
        // Pixels from the right (azimuth rising), so that the sweep moves one way.
        for pixel in (0..pixels).rev() {
            // Pieces of the window between silhouette edges, `samples` midpoints each.
            let center = strip.centers[pixel];
            let (lo, hi) = (center - half, center + half);
            let mut sum = 0.0;
            let mut p0 = lo;
            let mut next_break = look.breaks.partition_point(|&b| b <= lo);
            loop {
                let p1 = match look.breaks.get(next_break) {
                    Some(&b) if b < hi => {
                        next_break += 1;
                        b
                    }
                    _ => hi,
                };
                let width = p1 - p0;
                if width > 0.0 {
                    let facing = sweep.facing_over(look, p0, p1, facing);
                    for s in 0..samples {
                        let alpha = p0 + (s as f64 + 0.5) / samples as f64 * width;
                        let direction = look.turn(strip, pixel, alpha);
                        let value = self.column(
                            frame,
                            look,
                            direction,
                            facing,
                            strip.tan_half_band,
                            band,
                            sky,
                            ground,
                            scratch,
                        );
                        sum += value * (width / samples as f64);
                    }
                }
                if p1 >= hi {
                    break;
                }
                p0 = p1;
            }
            out[pixel] = sum / strip.width;
        }
        self.draw_impostors(
            look,
            frame,
            strip,
            band,
            sky,
            ground,
            (facing, &mut buffers.pieces, &mut buffers.profile),
            scratch,
            out,
        );
    }

    /// RGB at given tan-elevations along one azimuth (point samples, for paper optics).
    pub fn sample_column(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        direction: DVec2,
        alpha: f64,
        tans: &[f64],
        out: &mut [[f64; 3]],
    ) {
        let mut segments = Segments::new();
        with_workspace(|workspace| {
            let facing = look.facing(alpha, &mut workspace.buffers.facing);
            self.collect_segments(look, direction, facing, &mut segments);
        });
        for (t, rgb) in tans.iter().zip(out.iter_mut()) {
            *rgb = match segments.iter().find(|s| s.t0 <= *t && *t <= s.t1) {
                Some(segment) => self.shade_segment(frame, segment, look.eye, direction, *t),
                None => self.background(*t),
            };
        }
    }

    fn background(&self, tan: f64) -> [f64; 3] {
        match self.graph.background.ground {
            Some(ground) if tan < 0.0 => ground,
            _ => self.graph.background.sky,
        }
    }

    /// Segments of one column, sorted front to back (ties by object order: deterministic).
    ///
    /// A cap (a top seen from above, a bottom from below) is drawn at the depth of its far
    /// edge: whatever stands on it or floats over it, nearer than that edge, covers it first
    /// (a buoy on the floor, a lamp on its buoy). Its near part cannot be covered by such an
    /// object, whose silhouette starts at the cap's plane. Geometry below a floor inside
    /// the floor's footprint would show through; closed worlds have none. Inlined into each
    /// column: a call per column costs as much as an object's crossing.
    #[inline(always)]
    fn collect_segments(
        &self,
        look: &Look,
        direction: DVec2,
        facing: &[u32],
        segments: &mut impl SegmentSink,
    ) {
        let inverse = DVec2::ONE / direction;
        for &index in facing {
            collect_object(
                &look.objects[index as usize],
                index,
                look.eye.y,
                direction,
                inverse,
                segments,
            );
        }
    }

    /// The column's segments of `pieces` (an impostor's), ids from `first_id` up.
    fn collect_pieces(
        &self,
        look: &Look,
        direction: DVec2,
        (pieces, first_id): (&[EyeObject], u32),
        segments: &mut impl SegmentSink,
    ) {
        let inverse = DVec2::ONE / direction;
        for (k, object) in pieces.iter().enumerate() {
            collect_object(
                object,
                first_id + k as u32,
                look.eye.y,
                direction,
                inverse,
                segments,
            );
        }
    }

    /// Mean luminance over the band `[-T, T]` of one column, integrated exactly in angle;
    /// `facing` lists the objects whose azimuth interval holds the column.
    #[allow(clippy::too_many_arguments)]
    fn column(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        direction: DVec2,
        facing: &[u32],
        tan_half: f64,
        band: f64,
        sky: f64,
        ground: f64,
        scratch: &mut Scratch,
    ) -> f64 {
        let Scratch {
            segments,
            lit,
            free,
        } = scratch;
        let band = Band {
            tan_half,
            band,
            sky,
            ground,
        };
        if !frame.all_fast {
            return self.column_shaded(frame, look, direction, facing, &band, segments, free);
        }
        let lit = self.collect_lit(frame, look, direction, facing, lit);
        if let [one] = lit {
            if let Some(value) = band.composite_one((one.t0, one.t1), one.luminance) {
                return value;
            }
        }
        band.composite(lit, free, |segment, _, _| segment.luminance)
    }

    /// The column's segments with their luminance, where every face is fast shaded: known
    /// when a segment is made, so no faces are kept.
    #[inline]
    fn collect_lit<'l>(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        direction: DVec2,
        facing: &[u32],
        lit: &'l mut LitSegments,
    ) -> &'l [Lit] {
        lit.len = 0;
        let mut sink = LitSink {
            lit: &mut *lit,
            shades: &frame.shades,
        };
        self.collect_segments(look, direction, facing, &mut sink);
        lit.as_slice()
    }

    /// [`ColumnScene::column`] where some face is shaded per point (lights that move, or
    /// materials without fast shading): kept out of line, so that the fast path a crowd runs
    /// a thousand times a step stays small in the instruction cache.
    #[cold]
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn column_shaded(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        direction: DVec2,
        facing: &[u32],
        band: &Band,
        segments: &mut Segments,
        free: &mut Free,
    ) -> f64 {
        segments.len = 0;
        self.collect_segments(look, direction, facing, segments);
        band.composite(segments.iter(), free, |segment, middle, covered| {
            self.segment_luminance(frame, segment, look.eye, direction, middle, covered)
        })
    }

    /// What the column along `direction` shows, piece by piece (see [`Band::profile`]),
    /// appended to `out`; returns [`ColumnScene::column`]'s value.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn profile(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        direction: DVec2,
        facing: &[u32],
        band: &Band,
        scratch: &mut Scratch,
        out: &mut Vec<Shown>,
    ) -> f64 {
        let Scratch {
            segments,
            lit,
            free,
        } = scratch;
        if !frame.all_fast {
            return self.profile_shaded(
                frame,
                look,
                direction,
                facing,
                band,
                (segments, free),
                out,
            );
        }
        let lit = self.collect_lit(frame, look, direction, facing, lit);
        band.profile(lit, free, |s, _, _| s.luminance, out)
    }

    /// [`ColumnScene::profile`] where some face is shaded per point, out of line (see
    /// [`ColumnScene::column_shaded`]).
    #[cold]
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn profile_shaded(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        direction: DVec2,
        facing: &[u32],
        band: &Band,
        (segments, free): (&mut Segments, &mut Free),
        out: &mut Vec<Shown>,
    ) -> f64 {
        segments.len = 0;
        self.collect_segments(look, direction, facing, segments);
        band.profile(
            segments.iter(),
            free,
            |segment, middle, covered| {
                self.segment_luminance(frame, segment, look.eye, direction, middle, covered)
            },
            out,
        )
    }

    /// An impostor's effect on the band's mean along `direction` (through its centre), its
    /// faces composited into `profile` (what the column shows without it).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn impostor_effect(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        direction: DVec2,
        impostor: &Impostor,
        (profile, pieces): (&[Shown], &mut Vec<EyeObject>),
        band: &Band,
        scratch: &mut Scratch,
    ) -> f64 {
        impostor_pieces(frame, look, impostor, pieces);
        let id = look.objects.len() as u32;
        let Scratch {
            segments,
            lit,
            free,
        } = scratch;
        if !frame.all_fast {
            return self.impostor_effect_shaded(
                frame,
                look,
                direction,
                (profile, pieces, id),
                band,
                (segments, free),
            );
        }
        lit.len = 0;
        let mut sink = LitSink {
            lit,
            shades: &frame.shades,
        };
        self.collect_pieces(look, direction, (pieces, id), &mut sink);
        band.effect(profile, sink.lit.as_slice(), free, |s, _, _| s.luminance)
    }

    /// [`ColumnScene::impostor_effect`] where some face is shaded per point, out of line (see
    /// [`ColumnScene::column_shaded`]).
    #[cold]
    #[inline(never)]
    fn impostor_effect_shaded(
        &self,
        frame: &ColumnFrame,
        look: &Look,
        direction: DVec2,
        (profile, pieces, id): (&[Shown], &[EyeObject], u32),
        band: &Band,
        (segments, free): (&mut Segments, &mut Free),
    ) -> f64 {
        segments.len = 0;
        self.collect_pieces(look, direction, (pieces, id), segments);
        band.effect(
            profile,
            segments.iter(),
            free,
            |segment, middle, covered| {
                self.segment_luminance(frame, segment, look.eye, direction, middle, covered)
            },
        )
    }

    /// Luminance of a segment's face at tan-elevation `middle / covered` (the fast path skips
    /// RGB, and the point: its radiance depends on the normal alone).
    fn segment_luminance(
        &self,
        frame: &ColumnFrame,
        segment: &Segment,
        eye: DVec3,
        direction: DVec2,
        middle: f64,
        covered: f64,
    ) -> f64 {
        if let Some(fast) = frame.fast_shade(segment.primitive) {
            return match segment.face {
                Face::Side(n) => fast.luminance(DVec3::new(n.x, 0.0, n.y)),
                Face::Cap { up: true, .. } => fast.luminance(DVec3::Y),
                Face::Cap { up: false, .. } => fast.luminance(DVec3::NEG_Y),
            };
        }
        luminance(self.shade_segment(frame, segment, eye, direction, middle / covered))
    }

    /// Radiance of a segment's face at tan-elevation `t`.
    fn shade_segment(
        &self,
        frame: &ColumnFrame,
        segment: &Segment,
        eye: DVec3,
        direction: DVec2,
        t: f64,
    ) -> [f64; 3] {
        if let Some(fast) = frame.fast_shade(segment.primitive) {
            return match segment.face {
                Face::Side(n) => fast.radiance(DVec3::new(n.x, 0.0, n.y)),
                Face::Cap { up: true, .. } => fast.radiance(DVec3::Y),
                Face::Cap { up: false, .. } => fast.radiance(DVec3::NEG_Y),
            };
        }
        let (point, normal) = match segment.face {
            Face::Side(n) => {
                let d = segment.depth;
                (
                    DVec3::new(
                        eye.x + direction.x * d,
                        eye.y + t * d,
                        eye.z + direction.y * d,
                    ),
                    DVec3::new(n.x, 0.0, n.y),
                )
            }
            Face::Cap { y, up } => {
                let d = if t != 0.0 {
                    ((y - eye.y) / t).abs()
                } else {
                    1e6
                };
                let normal = if up { DVec3::Y } else { DVec3::NEG_Y };
                (
                    DVec3::new(eye.x + direction.x * d, y, eye.z + direction.y * d),
                    normal,
                )
            }
        };
        let material =
            &self.graph.materials[self.graph.primitives[segment.primitive as usize].material];
        let mut none = |_: DVec3, _: &LightKind| false;
        shade(material, None, point, normal, eye, &frame.lights, &mut none)
    }
}

/// An impostor's pieces as its eye sees them, into `pieces`.
fn impostor_pieces(
    frame: &ColumnFrame,
    look: &Look,
    impostor: &Impostor,
    pieces: &mut Vec<EyeObject>,
) {
    pieces.clear();
    let first = impostor.first_static as usize;
    for object in &frame.statics[first..first + impostor.pieces as usize] {
        pieces.push(eye_object(object, look.eye, impostor.lo, impostor.hi));
    }
}

/// One object's segments in the column along `direction` (`inverse`: its components'
/// reciprocals), under id `id`.
#[inline(always)]
fn collect_object(
    object: &EyeObject,
    id: u32,
    eye_y: f64,
    direction: DVec2,
    inverse: DVec2,
    segments: &mut impl SegmentSink,
) {
    let Some((t_in, t_out, normal)) = object.relative.cross(direction, inverse) else {
        return;
    };
    let (y0, y1) = (object.y0, object.y1);
    if t_in > 0.0 {
        let inv_in = 1.0 / t_in;
        if object.side {
            segments.insert(Segment {
                depth: t_in,
                t0: y0 * inv_in,
                t1: y1 * inv_in,
                object: id,
                primitive: object.primitive,
                face: Face::Side(normal),
            });
        }
        if object.top && y1 < 0.0 {
            segments.insert(Segment {
                depth: t_out,
                t0: y1 * inv_in,
                t1: y1 / t_out,
                object: id,
                primitive: object.primitive,
                face: Face::Cap {
                    y: y1 + eye_y,
                    up: true,
                },
            });
        }
        if object.bottom && y0 > 0.0 {
            segments.insert(Segment {
                depth: t_out,
                t0: y0 / t_out,
                t1: y0 * inv_in,
                object: id,
                primitive: object.primitive,
                face: Face::Cap {
                    y: y0 + eye_y,
                    up: false,
                },
            });
        }
    } else if y1 < 0.0 {
        // Standing over it (a floor): its top fills everything below its far edge.
        if object.top {
            segments.insert(Segment {
                depth: t_out,
                t0: f64::NEG_INFINITY,
                t1: y1 / t_out,
                object: id,
                primitive: object.primitive,
                face: Face::Cap {
                    y: y1 + eye_y,
                    up: true,
                },
            });
        }
    } else if y0 > 0.0 {
        if object.bottom {
            segments.insert(Segment {
                depth: t_out,
                t0: y0 / t_out,
                t1: f64::INFINITY,
                object: id,
                primitive: object.primitive,
                face: Face::Cap {
                    y: y0 + eye_y,
                    up: false,
                },
            });
        }
    } else {
        // Inside it (a round arena, a room): its inner faces, as the ray caster sees
        // them, at the exit distance.
        let inward = -object.relative.exit_normal(direction, t_out);
        if object.side {
            segments.insert(Segment {
                depth: t_out,
                t0: y0 / t_out,
                t1: y1 / t_out,
                object: id,
                primitive: object.primitive,
                face: Face::Side(inward),
            });
        }
        if object.top {
            segments.insert(Segment {
                depth: t_out,
                t0: y1 / t_out,
                t1: f64::INFINITY,
                object: id,
                primitive: object.primitive,
                face: Face::Cap {
                    y: y1 + eye_y,
                    up: false,
                },
            });
        }
        if object.bottom {
            segments.insert(Segment {
                depth: t_out,
                t0: f64::NEG_INFINITY,
                t1: y0 / t_out,
                object: id,
                primitive: object.primitive,
                face: Face::Cap {
                    y: y0 + eye_y,
                    up: true,
                },
            });
        }
    }
}

#[cfg(test)]
mod tests;
