//! Vision devices from the renderer to digital values: the Panoramic turret's optics (paper or
//! exact), photodetectors, filters and converter, and the K213 linear camera.
//!
//! Paper optics (1999): two flat perspective views, 75×7 each, 120° wide and 11° tall at their
//! centres, left view centred at +60°, right at −60°; each is warped to the cylinder
//! (x = f·tan θ, y = √(x² + f²)·tan φ, bilinear, edges clamped) and its 7 rows averaged. Two
//! errors are built in and measured by `regatta bench retina`: at θ = ±60° the band is twice
//! as tall as the flat view (clamping repeats its edge rows), and a flat column is 2.65° wide at
//! the centre, coarser than a 1.6° photodiode.
//!
//! Exact optics: each photodiode's 1.6° × 11° window integrated — analytically in elevation and
//! piecewise between silhouette edges in azimuth by the column renderer, or by a stratified
//! `samples × samples` grid of rays where the scene needs ray casting.

use glam::DVec3;

use crate::compile::graph::RenderGraph;
use crate::compile::plan::{Plan, RendererChoice};
use crate::compile::rig::{LinearCameraRig, Optics, PanoramicRig, Placement, Pose2};
use crate::render::column::{ColumnFrame, ColumnScene, KeptImpostors, Look, Strip};
use crate::render::raycast::{Prepared, RayCaster};
use crate::render::{Detail, Poses};
use crate::retina::{
    self, calibrate_i_bda, convert_scaled, luminance, normalize, Filter, FilterKind,
    FilterSettings, HALF_BAND, PIXELS, PIXEL_WIDTH,
};

/// Flat-view geometry of paper optics.
pub const FLAT_COLUMNS: usize = 75;
pub const FLAT_ROWS: usize = 7;
const VIEW_HALF_WIDTH: f64 = std::f64::consts::FRAC_PI_3; // 60°

/// The renderer a scene's plan chose, ready for frames.
pub enum Renderer<'g> {
    /// Boxed: the column renderer keeps its buffers, the ray caster only references.
    Columns(Box<ColumnScene<'g>>),
    Rays(RayCaster<'g>),
}

/// One frame of a renderer for one viewer.
pub enum View {
    Columns(ColumnFrame),
    Rays(Prepared),
}

/// A frame to render from, and for whom: a viewer's own [`View`], or one viewer of a frame
/// that every robot of a step shares.
#[derive(Clone, Copy)]
pub enum ViewOf<'v> {
    Columns(&'v ColumnFrame, Option<usize>),
    Rays(&'v Prepared),
}

impl View {
    /// This view, for the viewer it was made for.
    pub fn of(&self) -> ViewOf<'_> {
        match self {
            View::Columns(frame) => ViewOf::Columns(frame, frame.viewer),
            View::Rays(prepared) => ViewOf::Rays(prepared),
        }
    }
}

impl<'g> Renderer<'g> {
    /// The plan's renderer, or ray casting when `force_rays` (the reference).
    pub fn new(graph: &'g RenderGraph, plan: &Plan, force_rays: bool) -> Renderer<'g> {
        if force_rays || plan.renderer != RendererChoice::Columns {
            Renderer::Rays(RayCaster::new(graph, plan))
        } else {
            Renderer::Columns(Box::new(ColumnScene::new(graph, plan)))
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            Renderer::Columns(_) => "columns",
            Renderer::Rays(_) => "rays",
        }
    }

    pub fn view(&self, plan: &Plan, poses: &Poses, viewer: usize) -> View {
        match self {
            Renderer::Columns(scene) => View::Columns(scene.prepare(plan, poses, Some(viewer))),
            Renderer::Rays(caster) => View::Rays(caster.prepare(plan, poses, Some(viewer))),
        }
    }

    /// Places the world for every viewer of a step at once, into `shared` (its buffers
    /// reused): the column renderer's frame. The ray caster prepares per viewer
    /// ([`Renderer::view`]) and leaves `shared` empty. `placements`, when it has one per
    /// pose, gives the headings' sines and cosines already worked out. `crowd_looks_only`:
    /// every viewer of the frame looks with the crowd level of detail (other robots' tucked
    /// parts are then not placed: no look draws them).
    pub fn prepare_shared(
        &self,
        plan: &Plan,
        poses: &Poses,
        placements: &[Placement],
        crowd_looks_only: bool,
        shared: &mut Option<ColumnFrame>,
    ) {
        match self {
            Renderer::Columns(scene) => {
                let frame = shared.get_or_insert_with(|| scene.empty_frame());
                scene.prepare_placed(plan, poses, placements, crowd_looks_only, frame);
            }
            Renderer::Rays(_) => *shared = None,
        }
    }

    /// Mean luminance over each pixel window of a strip (exact optics). `stride` applies to
    /// the column renderer (see [`ColumnScene::integrate`]).
    #[allow(clippy::too_many_arguments)]
    pub fn integrate(
        &self,
        view: &View,
        eye: DVec3,
        heading: f64,
        strip: &Strip,
        detail: Detail,
        out: &mut [f64],
    ) {
        self.integrate_of(view.of(), eye, heading, strip, detail, out)
    }

    /// [`Renderer::integrate`] from any frame (see [`ViewOf`]).
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_of(
        &self,
        view: ViewOf,
        eye: DVec3,
        heading: f64,
        strip: &Strip,
        detail: Detail,
        out: &mut [f64],
    ) {
        match (self, view) {
            (Renderer::Columns(scene), ViewOf::Columns(frame, viewer)) => {
                scene.integrate_for(frame, viewer, eye, heading, strip, detail, out)
            }
            (Renderer::Rays(caster), ViewOf::Rays(frame)) => {
                let n = detail.samples.max(1);
                let half_band = libm::atan(strip.tan_half_band);
                for (pixel, pixel_out) in out.iter_mut().enumerate().take(strip.centers.len()) {
                    let mut sum = 0.0;
                    for i in 0..n {
                        let alpha = strip.centers[pixel]
                            + ((i as f64 + 0.5) / n as f64 - 0.5) * strip.width;
                        let world = heading + alpha;
                        let (cw, sw) = (libm::cos(world), libm::sin(world));
                        for j in 0..n {
                            let phi = ((j as f64 + 0.5) / n as f64 * 2.0 - 1.0) * half_band;
                            let (cp, sp) = (libm::cos(phi), libm::sin(phi));
                            sum += luminance(caster.rgb(
                                frame,
                                eye,
                                DVec3::new(cw * cp, sp, -sw * cp),
                            ));
                        }
                    }
                    *pixel_out = sum / (n * n) as f64;
                }
            }
            _ => unreachable!("a view comes from its own renderer"),
        }
    }

    /// RGB along one azimuth (relative to the heading) at several tan-elevations: one
    /// column of a flat view.
    #[allow(clippy::too_many_arguments)]
    fn flat_column(
        &self,
        view: ViewOf,
        look: Option<&Look>,
        eye: DVec3,
        heading: f64,
        alpha: f64,
        tans: &[f64],
        out: &mut [[f64; 3]],
    ) {
        match (self, view, look) {
            (Renderer::Columns(scene), ViewOf::Columns(frame, _), Some(look)) => {
                scene.sample_column(frame, look, look.direction(alpha), alpha, tans, out);
            }
            (Renderer::Rays(caster), ViewOf::Rays(frame), _) => {
                let world = heading + alpha;
                let (cw, sw) = (libm::cos(world), libm::sin(world));
                for (t, rgb) in tans.iter().zip(out.iter_mut()) {
                    *rgb = caster.rgb(frame, eye, DVec3::new(cw, *t, -sw));
                }
            }
            _ => unreachable!("a view comes from its own renderer"),
        }
    }

    /// The per-eye precomputation of the column renderer.
    fn look(&self, view: ViewOf, eye: DVec3, heading: f64) -> Option<Look> {
        match (self, view) {
            (Renderer::Columns(scene), ViewOf::Columns(frame, viewer)) => {
                Some(scene.look_for(frame, viewer, eye, heading))
            }
            _ => None,
        }
    }
}

/// Everything one retina update computes; every stage is kept.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RetinaOutput {
    /// Photocurrents (luminance) of the 150 photodiodes.
    pub luminance: Vec<f64>,
    /// Normalised image: luminance / mean.
    pub analog: Vec<f64>,
    /// True when every photodiode read 0: `analog` is then all zeros.
    pub dark: bool,
    /// Each enabled filter's output over the 150 pixels (empty when `filtered_unkept`).
    pub filtered: Vec<(FilterKind, Vec<f64>)>,
    /// Whether `filtered` is left empty, the filters' outputs going to a buffer of the
    /// thread's: a run that logs nothing reads only `digital` (1.2 kB less per retina).
    pub filtered_unkept: bool,
    /// Each enabled filter's converted output over the region of interest.
    pub digital: Vec<(FilterKind, Vec<u16>)>,
    pub i_bda: Vec<(FilterKind, f64)>,
    /// Paper optics only: the flat views (RGB, row-major 75×7) and the warped strips
    /// (luminance, 75×7), left view first.
    pub flat_views: Vec<Vec<[f64; 3]>>,
    pub warped: Vec<Vec<f64>>,
}

/// A Panoramic turret ready to update: strips precomputed, I_bda calibrated per filter.
pub struct Panoramic {
    pub rig: PanoramicRig,
    /// The retina's strip, the same for every turret: shared.
    strip: std::sync::Arc<Strip>,
    settings: FilterSettings,
    i_bda: Vec<(FilterKind, f64)>,
    /// The enabled filters, built for the retina's length, in the order of `i_bda`.
    filters: Vec<Filter>,
    /// With `crowdKeepDistance`, the impostors kept from one update to the next.
    kept: Option<KeptImpostors>,
}

/// A turret's kept impostors: with a crowd distance and `crowdKeepDistance`, else none.
fn kept_for(rig: &PanoramicRig) -> Option<KeptImpostors> {
    (rig.crowd_distance.is_finite() && rig.keep_distance > 0.0 && rig.keep_distance.is_finite())
        .then(|| KeptImpostors::new(rig.keep_distance))
}

impl Panoramic {
    pub fn new(rig: &PanoramicRig) -> Panoramic {
        Panoramic::new_like(rig, None)
    }

    /// [`Panoramic::new`], sharing `like`'s filters and calibration when its filter settings
    /// are the same (a swarm's turrets all are): the result is the same, built once.
    pub fn new_like(rig: &PanoramicRig, like: Option<&Panoramic>) -> Panoramic {
        let settings = FilterSettings {
            filters: rig.filters,
            lambda: rig.lambda,
            bandpass: rig.bandpass,
            bits: rig.bits,
            i_bda: rig.i_bda,
        };
        if let Some(like) = like.filter(|like| like.settings.same_bits(&settings)) {
            return Panoramic {
                rig: rig.clone(),
                strip: like.strip.clone(),
                settings,
                i_bda: like.i_bda.clone(),
                filters: like.filters.clone(),
                kept: kept_for(rig),
            };
        }
        let i_bda = rig
            .filters
            .iter()
            .map(|k| {
                (
                    k,
                    rig.i_bda
                        .unwrap_or_else(|| calibrate_i_bda(k, &settings, PIXELS)),
                )
            })
            .collect();
        let filters = rig
            .filters
            .iter()
            .map(|k| Filter::new(k, &settings, PIXELS))
            .collect();
        Panoramic {
            rig: rig.clone(),
            strip: retina_strip(),
            settings,
            i_bda,
            filters,
            kept: kept_for(rig),
        }
    }

    /// Changes filter settings (the API's set-λ, set-bits, enable/disable); I_bda follows.
    pub fn reconfigure(&mut self, rig: PanoramicRig) {
        *self = Panoramic::new(&rig);
    }

    /// Renders and processes one update for a robot at `pose` on a floor at `floor_y`.
    pub fn update(
        &mut self,
        renderer: &Renderer,
        view: &View,
        pose: Pose2,
        floor_y: f64,
        out: &mut RetinaOutput,
    ) {
        self.update_of(renderer, view.of(), pose, floor_y, out)
    }

    /// [`Panoramic::update`] from any frame (see [`ViewOf`]).
    pub fn update_of(
        &mut self,
        renderer: &Renderer,
        view: ViewOf,
        pose: Pose2,
        floor_y: f64,
        out: &mut RetinaOutput,
    ) {
        // The photocurrents go straight to the output: every optics writes all the pixels.
        let mut luminance = std::mem::take(&mut out.luminance);
        self.render_of(renderer, view, pose, floor_y, &mut luminance, out);
        self.process_photocurrents(&luminance, out);
        out.luminance = luminance;
    }

    /// [`Panoramic::update_of`] for a simulation, whose readers (controllers, logs) never
    /// read the photocurrents: they go to a buffer of the thread's and `out.luminance` stays
    /// empty (a crowd's retinas keep 1.2 kB less each). Every other output is the same.
    pub fn update_of_unkept(
        &mut self,
        renderer: &Renderer,
        view: ViewOf,
        pose: Pose2,
        floor_y: f64,
        out: &mut RetinaOutput,
    ) {
        PHOTOCURRENTS.with(|cell| {
            let mut luminance = cell.take();
            self.render_of(renderer, view, pose, floor_y, &mut luminance, out);
            self.process_photocurrents(&luminance, out);
            cell.set(luminance);
        });
        out.luminance.clear();
    }

    /// Renders the photocurrents of the eye at `pose` into `luminance`.
    fn render_of(
        &mut self,
        renderer: &Renderer,
        view: ViewOf,
        pose: Pose2,
        floor_y: f64,
        luminance: &mut Vec<f64>,
        out: &mut RetinaOutput,
    ) {
        let eye = DVec3::new(pose.x, floor_y + self.rig.height, pose.z);
        out.flat_views.clear();
        out.warped.clear();
        // Every optics writes every pixel (the column renderer clears its regions' pixels
        // itself): a buffer of the right length is not cleared first.
        luminance.resize(PIXELS, 0.0);
        match self.rig.optics {
            Optics::Exact => {
                let detail = Detail {
                    samples: self.rig.samples,
                    stride: self.rig.stride,
                    crowd_distance: self.rig.crowd_distance,
                    far_distance: self.rig.far_distance,
                };
                match (&mut self.kept, renderer, view) {
                    (Some(kept), Renderer::Columns(scene), ViewOf::Columns(frame, viewer)) => scene
                        .integrate_kept(
                            frame,
                            viewer,
                            eye,
                            pose.heading,
                            &self.strip,
                            detail,
                            kept,
                            luminance,
                        ),
                    _ => renderer.integrate_of(
                        view,
                        eye,
                        pose.heading,
                        &self.strip,
                        detail,
                        luminance,
                    ),
                }
            }
            Optics::Paper => paper(
                renderer,
                view,
                eye,
                pose.heading,
                self.rig.samples,
                self.rig.quantize_views,
                luminance,
                out,
            ),
        }
    }

    /// One update from photocurrents a batched backend rendered (no flat views kept).
    pub fn accept(&mut self, luminance: &[f64], out: &mut RetinaOutput) {
        out.luminance.clear();
        out.luminance.extend_from_slice(luminance);
        self.accept_unkept(luminance, out);
    }

    /// [`Panoramic::accept`] without keeping the photocurrents (see
    /// [`Panoramic::update_of_unkept`]).
    pub fn accept_unkept(&mut self, luminance: &[f64], out: &mut RetinaOutput) {
        out.flat_views.clear();
        out.warped.clear();
        self.process_photocurrents(luminance, out);
    }

    /// Photodetectors to digital, from `out.luminance`.
    pub fn process(&self, out: &mut RetinaOutput) {
        let luminance = std::mem::take(&mut out.luminance);
        self.process_photocurrents(&luminance, out);
        out.luminance = luminance;
    }

    /// Photodetectors to digital, from `luminance`.
    ///
    /// The stages are compiled twice (`wide.rs`): for AVX2, taken where the CPU has it (the
    /// filters' passes, the normalisation and the converter four lanes a register, not two,
    /// and no register spilled: about 2,000 fewer instructions a retina), and for baseline
    /// x86-64. Both give the same bits (`the_avx2_stages_give_the_baseline_bits`).
    fn process_photocurrents(&self, luminance: &[f64], out: &mut RetinaOutput) {
        #[cfg(target_arch = "x86_64")]
        if crate::wide::avx2() {
            // SAFETY: the CPU has AVX2, as just tested.
            return unsafe { self.process_photocurrents_avx2(luminance, out) };
        }
        self.process_photocurrents_inlined(luminance, out)
    }

    /// [`Panoramic::process_photocurrents`] compiled for AVX2: the stages below are inlined
    /// (`#[inline(always)]`, no thread-local closure between), or they would run their
    /// baseline copies; the zero-state passes, out of line, have an AVX2 copy of their own.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn process_photocurrents_avx2(&self, luminance: &[f64], out: &mut RetinaOutput) {
        self.process_photocurrents_inlined(luminance, out)
    }

    #[inline(always)]
    fn process_photocurrents_inlined(&self, luminance: &[f64], out: &mut RetinaOutput) {
        out.analog.resize(luminance.len(), 0.0);
        out.dark = !normalize(luminance, &mut out.analog);
        self.refilter(out);
    }

    /// The filters and the converter again, from `out.analog` (what a change of the filter
    /// settings changes).
    #[inline(always)]
    pub fn refilter(&self, out: &mut RetinaOutput) {
        if out.filtered_unkept {
            out.filtered.clear();
            // Taken out and put back, not used inside `with`: the filters stay inlined here.
            let mut filtered = FILTERED.with(|cell| cell.take());
            filtered.resize_with(self.i_bda.len(), || (FilterKind::Raw, Vec::new()));
            self.filter_into(&mut filtered, out);
            FILTERED.with(|cell| cell.set(filtered));
        } else {
            let mut filtered = std::mem::take(&mut out.filtered);
            // Buffers are reused from update to update: no allocation once warm.
            filtered.resize_with(self.i_bda.len(), || (FilterKind::Raw, Vec::new()));
            self.filter_into(&mut filtered, out);
            out.filtered = filtered;
        }
    }

    /// The filters into `filtered` (one entry per enabled filter) and the converter into
    /// `out.digital`, from `out.analog`.
    #[inline(always)]
    fn filter_into(&self, filtered: &mut [(FilterKind, Vec<f64>)], out: &mut RetinaOutput) {
        out.digital
            .resize_with(self.i_bda.len(), || (FilterKind::Raw, Vec::new()));
        if out.i_bda != self.i_bda {
            out.i_bda.clone_from(&self.i_bda);
        }
        let (first, last) = self.rig.roi;
        for (slot, (&(kind, i_bda), filter)) in self.i_bda.iter().zip(&self.filters).enumerate() {
            let (filtered_kind, filtered) = &mut filtered[slot];
            *filtered_kind = kind;
            filtered.resize(out.analog.len(), 0.0);
            if out.analog.len() == PIXELS {
                filter.apply(&out.analog, filtered);
            } else {
                retina::apply(kind, &self.settings, &out.analog, filtered);
            }
            let (digital_kind, digital) = &mut out.digital[slot];
            *digital_kind = kind;
            digital.clear();
            let last = last.min(filtered.len().saturating_sub(1));
            let top = ((1u32 << self.settings.bits) - 1) as f64;
            let (half, gain) = (top / 2.0, top / 2.0 / i_bda);
            digital.extend(
                filtered[first.min(last)..=last]
                    .iter()
                    .map(|&f| convert_scaled(f, half, gain, top)),
            );
        }
    }
}

thread_local! {
    /// The photocurrents of [`Panoramic::update_of_unkept`], one buffer per thread.
    static PHOTOCURRENTS: std::cell::Cell<Vec<f64>> = const { std::cell::Cell::new(Vec::new()) };
    /// The filters' outputs of a retina whose `filtered_unkept` is set, one set per thread.
    static FILTERED: std::cell::Cell<Vec<(FilterKind, Vec<f64>)>> =
        const { std::cell::Cell::new(Vec::new()) };
}

/// The EDI retina's strip, built once and shared by every Panoramic turret.
fn retina_strip() -> std::sync::Arc<Strip> {
    static STRIP: std::sync::OnceLock<std::sync::Arc<Strip>> = std::sync::OnceLock::new();
    STRIP
        .get_or_init(|| {
            let centers = (0..PIXELS).map(retina::pixel_azimuth).collect();
            std::sync::Arc::new(Strip::new(centers, PIXEL_WIDTH, HALF_BAND))
        })
        .clone()
}

/// The two flat views of paper optics: the left one centred at +60°, the right at −60°.
pub const VIEW_CENTERS: [f64; 2] = [VIEW_HALF_WIDTH, -VIEW_HALF_WIDTH];

/// Where paper optics sample a flat view, shared by every backend so that they agree: the
/// sub-columns (azimuth from the view's centre, and the slant √(x² + f²) that turns a row's
/// y into a tan-elevation), left to right, `samples` per column; and the sub-rows' y, top to
/// bottom, `samples` per row. Focal distance f = 1.
pub fn flat_samples(samples: usize) -> (Vec<(f64, f64)>, Vec<f64>) {
    let f = 1.0;
    let x_extent = f * libm::tan(VIEW_HALF_WIDTH);
    let y_extent = f * libm::tan(HALF_BAND);
    let n = samples.max(1);
    let mut columns = Vec::with_capacity(FLAT_COLUMNS * n);
    for c in 0..FLAT_COLUMNS {
        for si in 0..n {
            let x = x_extent
                * (2.0 * (c as f64 + (si as f64 + 0.5) / n as f64) / FLAT_COLUMNS as f64 - 1.0);
            columns.push((-libm::atan(x / f), (x * x + f * f).sqrt()));
        }
    }
    let mut rows = Vec::with_capacity(FLAT_ROWS * n);
    for r in 0..FLAT_ROWS {
        for sj in 0..n {
            rows.push(
                y_extent
                    * (1.0 - 2.0 * (r as f64 + (sj as f64 + 0.5) / n as f64) / FLAT_ROWS as f64),
            );
        }
    }
    (columns, rows)
}

/// The warp of paper optics: for view `v`, retina column `j` (0…74) and warped row `k`
/// (0…6), the continuous flat-view coordinates (u, w) to sample bilinearly, edges clamped.
pub fn warp_coordinates(v: usize, j: usize, k: usize) -> (f64, f64) {
    let f = 1.0;
    let x_extent = f * libm::tan(VIEW_HALF_WIDTH);
    let y_extent = f * libm::tan(HALF_BAND);
    let theta = retina::pixel_azimuth(v * FLAT_COLUMNS + j) - VIEW_CENTERS[v];
    let x = -f * libm::tan(theta);
    let u = (x / x_extent + 1.0) / 2.0 * FLAT_COLUMNS as f64 - 0.5;
    let phi = HALF_BAND - (k as f64 + 0.5) * 2.0 * HALF_BAND / FLAT_ROWS as f64;
    let y = (x * x + f * f).sqrt() * libm::tan(phi);
    let w = (1.0 - y / y_extent) / 2.0 * FLAT_ROWS as f64 - 0.5;
    (u, w)
}

/// An 8-bit frame buffer's channel: clamped to [0, 1] and rounded to 1/255.
pub fn quantize_channel(channel: f64) -> f64 {
    libm::round(channel.clamp(0.0, 1.0) * 255.0) / 255.0
}

/// The paper's optics: render, quantise, warp, average.
#[allow(clippy::too_many_arguments)]
fn paper(
    renderer: &Renderer,
    view: ViewOf,
    eye: DVec3,
    heading: f64,
    samples: usize,
    quantize: bool,
    luminance_out: &mut [f64],
    out: &mut RetinaOutput,
) {
    let n = samples.max(1);
    let (sub_columns, sub_rows) = flat_samples(n);
    let look = renderer.look(view, eye, heading);
    let mut tans = vec![0.0; FLAT_ROWS * n];
    let mut samples = vec![[0.0; 3]; FLAT_ROWS * n];
    for (v, view_center) in VIEW_CENTERS.into_iter().enumerate() {
        // Render the flat view: columns left to right (x grows to the right, azimuth falls),
        // rows top to bottom; each sub-column is one azimuth with all its rows.
        let mut flat = vec![[0.0; 3]; FLAT_COLUMNS * FLAT_ROWS];
        for c in 0..FLAT_COLUMNS {
            for si in 0..n {
                let (offset, slant) = sub_columns[c * n + si];
                let alpha = view_center + offset;
                for (tan, y) in tans.iter_mut().zip(&sub_rows) {
                    *tan = y / slant;
                }
                renderer.flat_column(
                    view,
                    look.as_ref(),
                    eye,
                    heading,
                    alpha,
                    &tans,
                    &mut samples,
                );
                for r in 0..FLAT_ROWS {
                    for sj in 0..n {
                        let rgb = samples[r * n + sj];
                        for k in 0..3 {
                            flat[r * FLAT_COLUMNS + c][k] += rgb[k] / (n * n) as f64;
                        }
                    }
                }
            }
        }
        if quantize {
            for rgb in &mut flat {
                *rgb = rgb.map(quantize_channel);
            }
        }
        let flat_luminance: Vec<f64> = flat.iter().map(|&c| luminance(c)).collect();
        // Warp to the cylinder and average the rows.
        let mut warped = vec![0.0; FLAT_COLUMNS * FLAT_ROWS];
        for j in 0..FLAT_COLUMNS {
            let pixel = v * FLAT_COLUMNS + j;
            let mut row_sum = 0.0;
            for k in 0..FLAT_ROWS {
                let (u, w) = warp_coordinates(v, j, k);
                let value = bilinear(&flat_luminance, u, w);
                warped[k * FLAT_COLUMNS + j] = value;
                row_sum += value;
            }
            luminance_out[pixel] = row_sum / FLAT_ROWS as f64;
        }
        out.flat_views.push(flat);
        out.warped.push(warped);
    }
}

/// Bilinear sample of a 75×7 image at continuous pixel coordinates, edges clamped.
fn bilinear(image: &[f64], u: f64, w: f64) -> f64 {
    let u = u.clamp(0.0, (FLAT_COLUMNS - 1) as f64);
    let w = w.clamp(0.0, (FLAT_ROWS - 1) as f64);
    let (c0, r0) = (u.floor() as usize, w.floor() as usize);
    let (c1, r1) = ((c0 + 1).min(FLAT_COLUMNS - 1), (r0 + 1).min(FLAT_ROWS - 1));
    let (fu, fw) = (u - c0 as f64, w - r0 as f64);
    let at = |c: usize, r: usize| image[r * FLAT_COLUMNS + c];
    (at(c0, r0) * (1.0 - fu) + at(c1, r0) * fu) * (1.0 - fw)
        + (at(c0, r1) * (1.0 - fu) + at(c1, r1) * fu) * fw
}

/// What a K213 update gives.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinearCameraOutput {
    pub luminance: Vec<f64>,
    pub analog: Vec<f64>,
    pub dark: bool,
    /// Grey levels: the light-level sensor acts as an iris, putting the mean at mid-scale:
    /// `min(2^b − 1, ⌊analog·(2^b − 1)/2 + ½⌋)`.
    pub digital: Vec<u16>,
    /// Mean luminance, 0…255 (linear, clamped).
    pub light_level: u16,
}

/// A K213 linear camera ready to update.
pub struct LinearCamera {
    pub rig: LinearCameraRig,
    strip: Strip,
    luminance: Vec<f64>,
}

impl LinearCamera {
    pub fn new(rig: &LinearCameraRig) -> LinearCamera {
        let width = rig.field_of_view / rig.pixels as f64;
        let centers = (0..rig.pixels)
            .map(|i| rig.field_of_view / 2.0 - (i as f64 + 0.5) * width)
            .collect();
        LinearCamera {
            rig: rig.clone(),
            strip: Strip::new(centers, width, rig.vertical_field_of_view / 2.0),
            luminance: vec![0.0; rig.pixels],
        }
    }

    pub fn update(
        &mut self,
        renderer: &Renderer,
        view: &View,
        pose: Pose2,
        floor_y: f64,
        out: &mut LinearCameraOutput,
    ) {
        self.update_of(renderer, view.of(), pose, floor_y, out)
    }

    /// [`LinearCamera::update`] from any frame (see [`ViewOf`]).
    pub fn update_of(
        &mut self,
        renderer: &Renderer,
        view: ViewOf,
        pose: Pose2,
        floor_y: f64,
        out: &mut LinearCameraOutput,
    ) {
        let eye = DVec3::new(pose.x, floor_y + self.rig.height, pose.z);
        renderer.integrate_of(
            view,
            eye,
            pose.heading,
            &self.strip,
            Detail::new(self.rig.samples, 1),
            &mut self.luminance,
        );
        out.luminance.clear();
        out.luminance.extend_from_slice(&self.luminance);
        Self::convert(&self.rig, out);
    }

    /// One update from photocurrents a batched backend rendered.
    pub fn accept(&mut self, luminance: &[f64], out: &mut LinearCameraOutput) {
        out.luminance.clear();
        out.luminance.extend_from_slice(luminance);
        Self::convert(&self.rig, out);
    }

    /// Photodetectors to grey levels and light level, from `out.luminance`.
    fn convert(rig: &LinearCameraRig, out: &mut LinearCameraOutput) {
        out.analog.resize(out.luminance.len(), 0.0);
        out.dark = !normalize(&out.luminance, &mut out.analog);
        let top = ((1u32 << rig.bits) - 1) as f64;
        out.digital = out
            .analog
            .iter()
            .map(|&a| libm::floor(a * top / 2.0 + 0.5).clamp(0.0, top) as u16)
            .collect();
        let mean = out.luminance.iter().sum::<f64>() / out.luminance.len().max(1) as f64;
        out.light_level = if mean.is_finite() {
            libm::round(mean.clamp(0.0, 1.0) * 255.0) as u16
        } else {
            0
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::rig::TurretRig;

    /// The AVX2 copies of the retina's stages and the baseline ones give the same bits: every
    /// filter (λ small and large), the converter at 6 and 12 bits, images smooth, rough,
    /// dark and with non-finite photocurrents. On a CPU without AVX2 both calls run the
    /// baseline, and the test says so.
    #[test]
    fn the_avx2_stages_give_the_baseline_bits() {
        if !crate::wide::avx2() {
            eprintln!("this CPU has no AVX2: both copies are the baseline one");
        }
        let world = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/regatta.wbt");
        let checked = regatta_schema::check_file(&world, true).expect("regatta.wbt readable");
        let compiled = crate::compile(&checked.scene);
        let Some(TurretRig::Panoramic(rig)) = &compiled.rig.robots[0].turret else {
            panic!("regatta.wbt's first robot has a Panoramic turret")
        };
        let mut random = crate::test_random::unit_stream(41);
        let mut images: Vec<Vec<f64>> = Vec::new();
        for _ in 0..40 {
            let scale = libm::pow(10.0, random() * 8.0 - 4.0);
            images.push((0..PIXELS).map(|_| random() * scale).collect());
        }
        // Smooth, with one bright spot: the filters' responses span the converter.
        images.push(
            (0..PIXELS)
                .map(|i| 1.0 + libm::sin(i as f64 / 9.0) * 0.3 + if i == 70 { 5.0 } else { 0.0 })
                .collect(),
        );
        images.push(vec![0.0; PIXELS]);
        let mut odd = vec![0.5; PIXELS];
        (odd[3], odd[80], odd[149]) = (f64::NAN, f64::INFINITY, -f64::INFINITY);
        images.push(odd);
        for (lambda, bits, unkept) in [(5.0, 6, false), (0.7, 6, true), (40.0, 12, false)] {
            let mut rig = rig.clone();
            (rig.lambda, rig.bandpass, rig.bits) = (lambda, (lambda, 4.0 * lambda), bits);
            FilterKind::ALL
                .into_iter()
                .for_each(|kind| rig.filters.insert(kind));
            let retina = Panoramic::new(&rig);
            for image in &images {
                let (mut chosen, mut baseline) = (RetinaOutput::default(), RetinaOutput::default());
                (chosen.filtered_unkept, baseline.filtered_unkept) = (unkept, unkept);
                retina.process_photocurrents(image, &mut chosen);
                crate::wide::baseline_only(|| retina.process_photocurrents(image, &mut baseline));
                let bits_of = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
                assert_eq!(
                    bits_of(&chosen.analog),
                    bits_of(&baseline.analog),
                    "λ {lambda}"
                );
                assert_eq!(chosen.dark, baseline.dark);
                assert_eq!(chosen.filtered.len(), baseline.filtered.len());
                for ((kind, a), (_, b)) in chosen.filtered.iter().zip(&baseline.filtered) {
                    assert_eq!(bits_of(a), bits_of(b), "{} at λ {lambda}", kind.name());
                }
                assert_eq!(chosen.digital, baseline.digital, "λ {lambda}, {bits} bits");
                assert_eq!(chosen.digital.len(), 5);
            }
        }
    }
}
