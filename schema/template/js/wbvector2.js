// wbvector2: two-dimensional vectors {x, y} (regatta's implementation of Webots' documented
// interface).

/** True when both components are equal. */
export function equal(vA, vB) {
  return vA.x === vB.x && vA.y === vB.y;
}

export function add(vA, vB) {
  return { x: vA.x + vB.x, y: vA.y + vB.y };
}

export function minus(vA, vB) {
  return { x: vA.x - vB.x, y: vA.y - vB.y };
}

/** The vector v scaled by the number s. */
export function multiply(v, s) {
  return { x: v.x * s, y: v.y * s };
}

export function norm(v) {
  return Math.sqrt(v.x * v.x + v.y * v.y);
}

export function distance(vA, vB) {
  return norm(minus(vA, vB));
}

/** The angle of the direction from vA to vB, in radians from the x axis (atan2). */
export function angle(vA, vB) {
  return Math.atan2(vB.y - vA.y, vB.x - vA.x);
}

/** The z component of the cross product. */
export function cross(vA, vB) {
  return vA.x * vB.y - vA.y * vB.x;
}

export function dot(vA, vB) {
  return vA.x * vB.x + vA.y * vB.y;
}

/** v divided by its norm; the zero vector stays zero. */
export function normalize(v) {
  const n = norm(v);
  return n === 0 ? { x: 0, y: 0 } : { x: v.x / n, y: v.y / n };
}

/** Where the segments [p1, p2] and [p3, p4] cross, or null when they do not. */
export function intersection(p1, p2, p3, p4) {
  const d1 = minus(p2, p1);
  const d2 = minus(p4, p3);
  const denominator = cross(d1, d2);
  if (denominator === 0) {
    return null;
  }
  const offset = minus(p3, p1);
  const t = cross(offset, d2) / denominator;
  const u = cross(offset, d1) / denominator;
  if (t < 0 || t > 1 || u < 0 || u > 1) {
    return null;
  }
  return { x: p1.x + t * d1.x, y: p1.y + t * d1.y };
}
