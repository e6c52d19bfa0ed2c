//! A strip of pixels to integrate: their centres and width in azimuth, and the half band in
//! elevation.

/// A strip of pixels to integrate: centres and width in azimuth relative to the viewer's
/// forward direction (counter-clockwise), and the half band in elevation.
#[derive(Clone, Debug)]
pub struct Strip {
    pub centers: Vec<f64>,
    pub width: f64,
    pub tan_half_band: f64,
    /// cos and sin of each centre.
    pub(super) directions: Vec<(f64, f64)>,
    /// Whether the windows tile the strip: centres one width apart, falling.
    pub(super) contiguous: bool,
    /// The lowest and highest relative azimuths the windows cover.
    pub(super) extent: (f64, f64),
    /// cos and sin of the extent's ends widened by [`SECTOR_MARGIN`]: where a look's sector
    /// of what faces a photodiode starts and ends, turned by the heading.
    pub(super) sector_ends: [(f64, f64); 2],
}

/// How far (rad) a look's sector reaches beyond the strip's extent.
pub(super) const SECTOR_MARGIN: f64 = 1e-6;

impl Strip {
    pub fn new(centers: Vec<f64>, width: f64, half_band: f64) -> Strip {
        let directions = centers
            .iter()
            .map(|&a| (libm::cos(a), libm::sin(a)))
            .collect();
        let contiguous = centers
            .windows(2)
            .all(|pair| ((pair[0] - pair[1]) - width).abs() <= 1e-9 * width);
        let lo = centers.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = centers.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let extent = (lo - width / 2.0, hi + width / 2.0);
        let end = |angle: f64| (libm::cos(angle), libm::sin(angle));
        Strip {
            sector_ends: [end(extent.0 - SECTOR_MARGIN), end(extent.1 + SECTOR_MARGIN)],
            extent,
            centers,
            width,
            tan_half_band: libm::tan(half_band),
            directions,
            contiguous,
        }
    }

    /// The relative azimuths the windows cover, lowest and highest (`None` when empty).
    #[inline]
    pub(super) fn extent(&self) -> Option<(f64, f64)> {
        (self.extent.0 <= self.extent.1).then_some(self.extent)
    }
}
