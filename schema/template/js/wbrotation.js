// wbrotation: rotations as axis-angle {x, y, z, a}, quaternions {w, x, y, z} and row-major
// 3×3 matrices [m0 … m8] (regatta's implementation of Webots' documented interface).

const EPSILON = 1e-12;

/** True when the two rotations turn every vector the same way. */
export function equal(rA, rB) {
  const qA = toQuaternion(rA);
  const qB = toQuaternion(rB);
  const dot = qA.w * qB.w + qA.x * qB.x + qA.y * qB.y + qA.z * qB.z;
  return Math.abs(Math.abs(dot) - 1) < 1e-9;
}

/** The axis-angle of quaternion q (normalised first). */
export function fromQuaternion(q) {
  const n = Math.sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (n === 0) {
    return { x: 0, y: 0, z: 1, a: 0 };
  }
  const w = Math.min(1, Math.max(-1, q.w / n));
  const s = Math.sqrt(1 - w * w);
  if (s < EPSILON) {
    return { x: 0, y: 0, z: 1, a: 0 };
  }
  return { x: q.x / n / s, y: q.y / n / s, z: q.z / n / s, a: 2 * Math.acos(w) };
}

/** The unit quaternion of rotation r (its axis normalised). */
export function toQuaternion(r) {
  const n = Math.sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
  if (n === 0) {
    return { w: 1, x: 0, y: 0, z: 0 };
  }
  const half = r.a / 2;
  const s = Math.sin(half) / n;
  return { w: Math.cos(half), x: r.x * s, y: r.y * s, z: r.z * s };
}

/** The axis-angle of a rotation matrix (row-major, 9 numbers). */
export function fromMatrix3(m) {
  const trace = m[0] + m[4] + m[8];
  let q;
  if (trace > 0) {
    const s = 2 * Math.sqrt(trace + 1);
    q = { w: s / 4, x: (m[7] - m[5]) / s, y: (m[2] - m[6]) / s, z: (m[3] - m[1]) / s };
  } else if (m[0] > m[4] && m[0] > m[8]) {
    const s = 2 * Math.sqrt(1 + m[0] - m[4] - m[8]);
    q = { w: (m[7] - m[5]) / s, x: s / 4, y: (m[1] + m[3]) / s, z: (m[2] + m[6]) / s };
  } else if (m[4] > m[8]) {
    const s = 2 * Math.sqrt(1 + m[4] - m[0] - m[8]);
    q = { w: (m[2] - m[6]) / s, x: (m[1] + m[3]) / s, y: s / 4, z: (m[5] + m[7]) / s };
  } else {
    const s = 2 * Math.sqrt(1 + m[8] - m[0] - m[4]);
    q = { w: (m[3] - m[1]) / s, x: (m[2] + m[6]) / s, y: (m[5] + m[7]) / s, z: s / 4 };
  }
  return fromQuaternion(q);
}

/** The row-major matrix of rotation r. */
export function toMatrix3(r) {
  const q = toQuaternion(r);
  const { w, x, y, z } = q;
  return [
    1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
    2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
    2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
  ];
}

/** True when r turns nothing. */
export function isIdentity(r) {
  return Math.abs(Math.sin(r.a / 2)) < EPSILON ||
    (r.x === 0 && r.y === 0 && r.z === 0);
}

/** r with a unit axis and its angle in (-π, π]. */
export function normalize(r) {
  const n = Math.sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
  if (n === 0) {
    return { x: 0, y: 0, z: 1, a: 0 };
  }
  let a = r.a % (2 * Math.PI);
  if (a > Math.PI) {
    a -= 2 * Math.PI;
  } else if (a <= -Math.PI) {
    a += 2 * Math.PI;
  }
  return { x: r.x / n, y: r.y / n, z: r.z / n, a: a };
}

function multiplyQuaternions(p, q) {
  return {
    w: p.w * q.w - p.x * q.x - p.y * q.y - p.z * q.z,
    x: p.w * q.x + p.x * q.w + p.y * q.z - p.z * q.y,
    y: p.w * q.y - p.x * q.z + p.y * q.w + p.z * q.x,
    z: p.w * q.z + p.x * q.y - p.y * q.x + p.z * q.w,
  };
}

/** The rotation rA·rB: rB turns first, then rA. */
export function combine(rA, rB) {
  return fromQuaternion(multiplyQuaternions(toQuaternion(rA), toQuaternion(rB)));
}

export function rotateVector3ByMatrix3(m, v) {
  return {
    x: m[0] * v.x + m[1] * v.y + m[2] * v.z,
    y: m[3] * v.x + m[4] * v.y + m[5] * v.z,
    z: m[6] * v.x + m[7] * v.y + m[8] * v.z,
  };
}

export function rotateVector3ByRotation(r, v) {
  return rotateVector3ByMatrix3(toMatrix3(r), v);
}

export function rotateVector3ByQuaternion(q, v) {
  const p = multiplyQuaternions(multiplyQuaternions(q, { w: 0, x: v.x, y: v.y, z: v.z }),
                                { w: q.w, x: -q.x, y: -q.y, z: -q.z });
  return { x: p.x, y: p.y, z: p.z };
}
