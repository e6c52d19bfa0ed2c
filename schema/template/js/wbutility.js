// wbutility: small helpers (regatta's implementation of Webots' documented interface).
// Messages go to the console that regatta reports after the template ran.

/** Prints message as an error when statement is false. */
export function assert(statement, message) {
  if (!statement) {
    console.error(message);
  }
}

export function error(message) {
  console.error(message);
}

export function info(message) {
  console.log(message);
}

/** An independent copy of plain data (objects, arrays, numbers, strings, booleans). */
export function deepCopy(original) {
  if (Array.isArray(original)) {
    return original.map(deepCopy);
  }
  if (original !== null && typeof original === 'object') {
    const copy = {};
    for (const key of Object.keys(original)) {
      copy[key] = deepCopy(original[key]);
    }
    return copy;
  }
  return original;
}

export function degreesToRadians(angle) {
  return angle * Math.PI / 180;
}

export function radiansToDegrees(angle) {
  return angle * 180 / Math.PI;
}

export function isScalar(s) {
  return typeof s === 'number';
}

function hasNumbers(value, keys) {
  return value !== null && typeof value === 'object' &&
    Object.keys(value).length === keys.length &&
    keys.every((key) => typeof value[key] === 'number');
}

export function isVector2(v) {
  return hasNumbers(v, ['x', 'y']);
}

export function isVector3(v) {
  return hasNumbers(v, ['x', 'y', 'z']);
}

export function isAxisAngle(r) {
  return hasNumbers(r, ['x', 'y', 'z', 'a']);
}

export function isQuaternion(q) {
  return hasNumbers(q, ['w', 'x', 'y', 'z']);
}

export function isMatrix3(m) {
  return hasNumbers(m, ['0', '1', '2', '3', '4', '5', '6', '7', '8']);
}

/** True when array is an array of points of dim (2 or 3) coordinates. */
export function isArrayOfPoints(array, dim) {
  if (!Array.isArray(array)) {
    return false;
  }
  const test = dim === 2 ? isVector2 : dim === 3 ? isVector3 : null;
  return test !== null && array.every(test);
}
