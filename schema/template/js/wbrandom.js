// wbrandom: seeded pseudo-random numbers (regatta's implementation of Webots' documented
// interface). A linear congruential generator modulo 2^32 (multiplier 1664525, increment
// 1013904223); every product stays below 2^53, so each step is exact in doubles. The default
// seed is the one regatta gives the template (derived from the world's seed), so a template
// that never calls seed() is reproducible.
let state = (globalThis.__regatta_wbrandom_seed ?? 0) >>> 0;

const MODULUS = 4294967296;

function next() {
  state = (1664525 * state + 1013904223) % MODULUS;
  return state / MODULUS;
}

/** Sets the generator's seed (an integer; fractions are dropped). */
export function seed(s) {
  state = Math.floor(Math.abs(Number(s))) % MODULUS;
}

/** A number in [min, max]: real() in [0, 1], real(max) in [0, max]. */
export function real(min, max) {
  if (min === undefined) {
    return next();
  }
  if (max === undefined) {
    max = min;
    min = 0;
  }
  return min + next() * (max - min);
}

/** An integer in [min, max]: integer() in [0, 2^24 - 1], integer(max) in [0, max]. */
export function integer(min, max) {
  if (min === undefined) {
    min = 0;
    max = 16777215;
  } else if (max === undefined) {
    max = min;
    min = 0;
  }
  min = Math.ceil(min);
  max = Math.floor(max);
  return min + Math.floor(next() * (max - min + 1));
}
