// regatta's template sandbox, run before each template (a script, not a module).
// It replaces what would reach outside the template or depend on the machine: the clock, the
// random source, the console, the file functions and the transcendental functions of Math.
(function (global) {
  'use strict';
  const seed = global.__regatta_seed >>> 0;
  delete global.__regatta_seed;
  const libm = global.__regatta_libm;
  delete global.__regatta_libm;

  Object.defineProperty(global, '__regatta_wbrandom_seed', { value: seed });

  // The clock stands still at an instant derived from the seed (milliseconds after 1 January
  // 2020, UTC), so that `wbrandom.seed(Date.now())` is reproducible; local time is UTC.
  const NativeDate = global.Date;
  const now = Date.UTC(2020, 0, 1) + seed;
  const proto = NativeDate.prototype;
  const localToUtc = ['FullYear', 'Month', 'Date', 'Day', 'Hours', 'Minutes', 'Seconds', 'Milliseconds'];
  for (const part of localToUtc) {
    proto['get' + part] = proto['getUTC' + part];
    if (part !== 'Day') {
      proto['set' + part] = proto['setUTC' + part];
    }
  }
  proto.getTimezoneOffset = function () { return 0; };
  proto.toString = proto.toUTCString;
  proto.toLocaleString = proto.toUTCString;
  function StillDate(...args) {
    if (!new.target) {
      return new NativeDate(now).toUTCString();
    }
    if (args.length === 0) {
      return Reflect.construct(NativeDate, [now], new.target);
    }
    if (args.length >= 2) {
      return Reflect.construct(NativeDate, [NativeDate.UTC(...args)], new.target);
    }
    return Reflect.construct(NativeDate, args, new.target);
  }
  StillDate.prototype = proto;
  StillDate.now = function () { return now; };
  StillDate.UTC = NativeDate.UTC;
  StillDate.parse = NativeDate.parse;
  Object.defineProperty(proto, 'constructor', { value: StillDate, writable: true, configurable: true });
  global.Date = StillDate;

  // Math.random: a 32-bit counter-based generator, seeded.
  let state = (seed ^ 0x9e3779b9) >>> 0;
  global.Math.random = function () {
    state = (state + 0x6d2b79f5) >>> 0;
    let t = Math.imul(state ^ (state >>> 15), state | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };

  // Transcendental functions from libm, with JavaScript's argument conversion.
  for (const name of ['sin', 'cos', 'tan', 'asin', 'acos', 'atan', 'sinh', 'cosh', 'tanh',
                      'asinh', 'acosh', 'atanh', 'exp', 'expm1', 'log', 'log1p', 'log2',
                      'log10', 'cbrt']) {
    const f = libm[name];
    global.Math[name] = function (x) { return f(+x); };
  }
  global.Math.atan2 = function (y, x) { return libm.atan2(+y, +x); };
  global.Math.pow = function (x, y) {
    x = +x;
    y = +y;
    // Where C's pow and JavaScript's differ.
    if (y !== y || ((x === 1 || x === -1) && !Number.isFinite(y))) {
      return NaN;
    }
    return libm.pow(x, y);
  };

  // console: lines kept for the caller (at most 1000).
  const lines = [];
  global.__regatta_console = lines;
  const print = (warning) => function (...args) {
    if (lines.length < 1000) {
      lines.push([warning, args.map((a) => (typeof a === 'string' ? a : JSON.stringify(a) ?? String(a))).join(' ')]);
    }
  };
  global.console = {
    log: print(false), info: print(false), debug: print(false),
    warn: print(true), error: print(true),
  };

  // wbfile: Webots' file functions. Templates read and write no files in regatta.
  const noFiles = function () {
    throw new Error('wbfile is not available: regatta templates read and write no files');
  };
  global.wbfile = { fileExists: noFiles, readTextFile: noFiles, writeTextFile: noFiles };
})(globalThis);
