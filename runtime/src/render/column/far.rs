//! An impostor's faces where each has fast shading, built straight from its footprint: a far
//! round object seen from outside shows, along the column through its centre, each piece's
//! side at the entry distance d − r facing the eye, and a cap below (or above) the eye at the
//! exit distance d + r. The general path (`integrate.rs`) crosses each piece with the column as
//! it would any object, with a square root per piece and the sink's sorting: about half an
//! impostor's cost at 1000 robots, for the same faces (to rounding).

use glam::{DVec2, DVec3};

use super::impostor::Impostor;
use super::photodiode::{Band, Free, Lit, Shown};
use super::scene::ColumnFrame;

/// Most faces an impostor keeps here (a side and two caps per piece: a buoy and its lamp); one
/// with more takes the general path.
const MOST_FACES: usize = 6;

/// The change in the band's mean along `direction` (through the impostor's centre) when its
/// faces join what `profile` shows, its pieces numbered from `first_id` (ties in depth go by
/// them, as in a column); `None` when a piece has no fast shading or the faces are too many.
#[allow(clippy::too_many_arguments)]
pub(super) fn fast_effect(
    frame: &ColumnFrame,
    impostor: &Impostor,
    eye_y: f64,
    direction: DVec2,
    first_id: u32,
    profile: &[Shown],
    band: &Band,
    free: &mut Free,
) -> Option<f64> {
    let first = impostor.first_static as usize;
    let pieces = frame.statics.get(first..first + impostor.pieces as usize)?;
    // An impostor lies beyond the crowd distance: the eye is outside its footprint.
    let (t_in, t_out) = (
        impostor.distance - impostor.radius,
        impostor.distance + impostor.radius,
    );
    if !(t_in > 0.0) {
        return None;
    }
    let inv_in = 1.0 / t_in;
    let normal = DVec3::new(-direction.x, 0.0, -direction.y);
    let mut faces = [Lit::default(); MOST_FACES];
    let mut count = 0;
    let mut push = |face: Lit| {
        if count == MOST_FACES {
            return false;
        }
        // Front to back, equal depths by object, each object's faces in the order they come
        // (a column's order).
        let mut i = count;
        while i > 0
            && (faces[i - 1].depth > face.depth
                || (faces[i - 1].depth == face.depth && faces[i - 1].object > face.object))
        {
            faces[i] = faces[i - 1];
            i -= 1;
        }
        faces[i] = face;
        count += 1;
        true
    };
    for (k, piece) in pieces.iter().enumerate() {
        let fast = frame.fast_shade(piece.primitive as u32)?;
        let object = first_id + k as u32;
        let (y0, y1) = (piece.y0 - eye_y, piece.y1 - eye_y);
        let mut kept = true;
        if piece.side {
            kept &= push(Lit {
                depth: t_in,
                t0: y0 * inv_in,
                t1: y1 * inv_in,
                luminance: fast.luminance(normal),
                object,
            });
        }
        if piece.top && y1 < 0.0 {
            kept &= push(Lit {
                depth: t_out,
                t0: y1 * inv_in,
                t1: y1 / t_out,
                luminance: fast.up_luminance,
                object,
            });
        }
        if piece.bottom && y0 > 0.0 {
            kept &= push(Lit {
                depth: t_out,
                t0: y0 / t_out,
                t1: y0 * inv_in,
                luminance: fast.down_luminance,
                object,
            });
        }
        if !kept {
            return None;
        }
    }
    Some(band.effect(profile, &faces[..count], free, |face, _, _| face.luminance))
}
