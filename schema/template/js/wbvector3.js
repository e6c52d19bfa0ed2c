// wbvector3: three-dimensional vectors {x, y, z} (regatta's implementation of Webots'
// documented interface).

export function equal(vA, vB) {
  return vA.x === vB.x && vA.y === vB.y && vA.z === vB.z;
}

export function add(vA, vB) {
  return { x: vA.x + vB.x, y: vA.y + vB.y, z: vA.z + vB.z };
}

export function minus(vA, vB) {
  return { x: vA.x - vB.x, y: vA.y - vB.y, z: vA.z - vB.z };
}

/** The vector v scaled by the number s. */
export function multiply(v, s) {
  return { x: v.x * s, y: v.y * s, z: v.z * s };
}

export function norm(v) {
  return Math.sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
}

export function distance(vA, vB) {
  return norm(minus(vA, vB));
}

export function cross(vA, vB) {
  return {
    x: vA.y * vB.z - vA.z * vB.y,
    y: vA.z * vB.x - vA.x * vB.z,
    z: vA.x * vB.y - vA.y * vB.x,
  };
}

export function dot(vA, vB) {
  return vA.x * vB.x + vA.y * vB.y + vA.z * vB.z;
}

/** v divided by its norm; the zero vector stays zero. */
export function normalize(v) {
  const n = norm(v);
  return n === 0 ? { x: 0, y: 0, z: 0 } : { x: v.x / n, y: v.y / n, z: v.z / n };
}
