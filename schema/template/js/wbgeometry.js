// wbgeometry: points, polygons and curves in the plane and in space (regatta's
// implementation of Webots' documented interface).

/**
 * div points {x, y} on the circle of the given radius about center, the first at angle shift
 * (radians from the x axis), counter-clockwise.
 */
export function circle(radius, div, center, shift) {
  const c = center ?? { x: 0, y: 0 };
  const start = shift ?? 0;
  const points = [];
  for (let i = 0; i < div; ++i) {
    const angle = start + 2 * Math.PI * i / div;
    points.push({ x: c.x + radius * Math.cos(angle), y: c.y + radius * Math.sin(angle) });
  }
  return points;
}

/** True when p is inside polygon (an array of {x, y}; even-odd rule). */
export function isPoint2InPolygon(p, polygon) {
  let inside = false;
  for (let i = 0, j = polygon.length - 1; i < polygon.length; j = i++) {
    const a = polygon[i];
    const b = polygon[j];
    if ((a.y > p.y) !== (b.y > p.y) &&
        p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) {
      inside = !inside;
    }
  }
  return inside;
}

/** The point of points closest to reference (the first of equals). */
export function findClosestPoint2InArray(reference, points) {
  let best = null;
  let bestDistance = Infinity;
  for (const point of points) {
    const dx = point.x - reference.x;
    const dy = point.y - reference.y;
    const distance = dx * dx + dy * dy;
    if (distance < bestDistance) {
      best = point;
      bestDistance = distance;
    }
  }
  return best;
}

/** True when the polygon's points turn clockwise (negative signed area). */
export function isPoint2ArrayClockwise(points) {
  let twiceArea = 0;
  for (let i = 0; i < points.length; ++i) {
    const a = points[i];
    const b = points[(i + 1) % points.length];
    twiceArea += a.x * b.y - b.x * a.y;
  }
  return twiceArea < 0;
}

// A uniform cubic B-spline through its end points: the first and last control points are
// taken three times, so that the curve starts and ends on them. Each of its n + 1 spans gives
// `subdivision` points, and the last control point closes the curve.
function bSpline(points, subdivision, keys) {
  if (points.length < 2) {
    return points.map((p) => Object.assign({}, p));
  }
  const steps = Math.max(1, Math.floor(subdivision));
  const control = [points[0], points[0], ...points, points[points.length - 1], points[points.length - 1]];
  const result = [];
  for (let span = 0; span + 3 < control.length; ++span) {
    const [p0, p1, p2, p3] = [control[span], control[span + 1], control[span + 2], control[span + 3]];
    for (let i = 0; i < steps; ++i) {
      const t = i / steps;
      const b0 = (1 - t) * (1 - t) * (1 - t) / 6;
      const b1 = (3 * t * t * t - 6 * t * t + 4) / 6;
      const b2 = (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6;
      const b3 = t * t * t / 6;
      const point = {};
      for (const k of keys) {
        point[k] = b0 * p0[k] + b1 * p1[k] + b2 * p2[k] + b3 * p3[k];
      }
      result.push(point);
    }
  }
  const last = {};
  for (const k of keys) {
    last[k] = points[points.length - 1][k];
  }
  result.push(last);
  return result;
}

/** A cubic B-spline through points {x, y}, each span cut in subdivision pieces. */
export function bSpline2(points, subdivision) {
  return bSpline(points, subdivision, ['x', 'y']);
}

/** A cubic B-spline through points {x, y, z}, each span cut in subdivision pieces. */
export function bSpline3(points, subdivision) {
  return bSpline(points, subdivision, ['x', 'y', 'z']);
}
