// Ray casting of the render graph for vision devices, many views per dispatch.
//
// `trace_views`: one invocation per (view, pixel). A paper-mode flat view (75×7) writes its
// pixels' luminance to `flat`; a K213 strip writes each pixel's window mean to `outputs`.
// `warp_views`: one invocation per (flat view, retina column): bilinear warp to the cylinder
// and the mean of the 7 warped rows, written to `outputs`.
//
// Everything mirrors the CPU ray caster (`runtime/src/render/raycast.rs`, `geometry.rs`,
// `render/mod.rs::shade`) in f32, with positions relative to each scene's own origin so that
// a world far from (0, 0, 0) keeps its precision.

struct Prim {
    inv0: vec4<f32>,
    inv1: vec4<f32>,
    inv2: vec4<f32>,
    params: vec4<f32>,
    bmin: vec4<f32>,
    bmax: vec4<f32>,
    // kind, flags, material, owner (0xffffffff: static)
    info: vec4<u32>,
    // mesh: first triangle, triangle count
    mesh: vec4<u32>,
}

struct Material {
    diffuse: vec4<f32>,  // w: ambientIntensity
    specular: vec4<f32>, // w: shininess
    emissive: vec4<f32>, // w: 1 when unlit
}

struct Light {
    color: vec4<f32>,       // w: intensity
    location: vec4<f32>,    // w: radius
    direction: vec4<f32>,   // w: ambientIntensity
    attenuation: vec4<f32>, // w: beamWidth
    spot: vec4<f32>,        // x: cutOffAngle
    info: vec4<u32>,        // kind, owner, shadows
}

struct Scene {
    ranges: vec4<u32>, // first primitive, primitive count, first light, light count
    sky: vec4<f32>,
    ground: vec4<f32>, // w: 1 when the world has ground colours
}

struct View {
    a: vec4<u32>,   // instance, robot, kind (0 flat, 1 strip), output offset
    b: vec4<u32>,   // pixels, samples, quantize, flat offset
    c: vec4<u32>,   // column table, row table, warp view (0 left, 1 right)
    eye: vec4<f32>, // eye (scene-relative), heading
    geo: vec4<f32>, // flat: view centre; strip: first pixel's centre + width/2, width, half band
}

const KIND_BOX: u32 = 0u;
const KIND_CYLINDER: u32 = 1u;
const KIND_CONE: u32 = 2u;
const KIND_SPHERE: u32 = 3u;
const KIND_MESH: u32 = 4u;

const FLAG_SIDE: u32 = 1u;
const FLAG_BOTTOM: u32 = 2u;
const FLAG_TOP: u32 = 4u;
const FLAG_VISIBLE: u32 = 8u;
const FLAG_OWN_VISIBLE: u32 = 16u;

const STATIC_OWNER: u32 = 0xffffffffu;
const MISS: f32 = 3.0e38;
const FLAT_COLUMNS: u32 = 75u;
const FLAT_ROWS: u32 = 7u;
const FLAT_PIXELS: u32 = 525u;
// Shadow rays start this far off the surface (m): f32 cannot use the CPU's 1e-9.
const SHADOW_OFFSET: f32 = 1.0e-5;

@group(0) @binding(0) var<storage, read> prims: array<Prim>;
@group(0) @binding(1) var<storage, read> materials: array<Material>;
@group(0) @binding(2) var<storage, read> lights: array<Light>;
@group(0) @binding(3) var<storage, read> scenes: array<Scene>;
// Three corners then the triangle's colour (w: 1 when it has one).
@group(0) @binding(4) var<storage, read> triangles: array<vec4<f32>>;
// Sampling tables: flat-view sub-columns (azimuth offset, 1/slant), sub-rows (y), and
// the warp's (u, w) per view, column and row.
@group(0) @binding(5) var<storage, read> tables: array<f32>;
// Per instance: scene, first pose, robot count.
@group(1) @binding(0) var<storage, read> instances: array<vec4<u32>>;
// Per robot: (x, floor y, z, _), (cos heading, sin heading, _, _).
@group(1) @binding(1) var<storage, read> poses: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> views: array<View>;
@group(1) @binding(3) var<storage, read_write> flat: array<f32>;
@group(1) @binding(4) var<storage, read_write> outputs: array<f32>;
@group(1) @binding(5) var<uniform> batch: vec4<u32>; // view count, warp table offset

fn safe_recip(d: vec3<f32>) -> vec3<f32> {
    let tiny = 1.0e-30;
    return vec3<f32>(
        select(1.0 / d.x, select(1.0e30, -1.0e30, d.x < 0.0), abs(d.x) < tiny),
        select(1.0 / d.y, select(1.0e30, -1.0e30, d.y < 0.0), abs(d.y) < tiny),
        select(1.0 / d.z, select(1.0e30, -1.0e30, d.z < 0.0), abs(d.z) < tiny),
    );
}

fn signum(x: f32) -> f32 {
    return select(1.0, -1.0, x < 0.0);
}

// Stable quadratic roots of a·t² + 2b·t + c (b is the half coefficient).
fn roots(a: f32, b: f32, disc: f32, c: f32) -> vec2<f32> {
    let sq = sqrt(disc);
    let q = -b - select(sq, -sq, b < 0.0);
    return vec2<f32>(q / a, c / q);
}

fn finite(t: f32) -> bool {
    return t == t && abs(t) < MISS;
}

// Each returns (t, normal); t = MISS when nothing is hit within t_max.
fn ray_box(o: vec3<f32>, d: vec3<f32>, half: vec3<f32>, t_max: f32) -> vec4<f32> {
    let inv = safe_recip(d);
    let t0 = (-half - o) * inv;
    let t1 = (half - o) * inv;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let enter = max(max(near.x, near.y), near.z);
    let exit = min(min(far.x, far.y), far.z);
    if enter > exit || exit < 0.0 {
        return vec4<f32>(MISS);
    }
    // From inside, the inner faces are hits too (as on the CPU).
    var t = exit;
    var axis = far;
    if enter >= 0.0 {
        t = enter;
        axis = near;
    }
    if t > t_max {
        return vec4<f32>(MISS);
    }
    if axis.x == t {
        return vec4<f32>(t, -signum(d.x), 0.0, 0.0);
    }
    if axis.y == t {
        return vec4<f32>(t, 0.0, -signum(d.y), 0.0);
    }
    return vec4<f32>(t, 0.0, 0.0, -signum(d.z));
}

fn ray_sphere(o: vec3<f32>, d: vec3<f32>, r: f32, t_max: f32) -> vec4<f32> {
    let a = dot(d, d);
    let b = dot(o, d);
    let c = dot(o, o) - r * r;
    let disc = b * b - a * c;
    if disc < 0.0 || a == 0.0 {
        return vec4<f32>(MISS);
    }
    let ts = roots(a, b, disc, c);
    let t0 = min(ts.x, ts.y);
    let t1 = max(ts.x, ts.y);
    let t = select(t1, t0, t0 >= 0.0);
    if !(t >= 0.0 && t <= t_max) || !finite(t) {
        return vec4<f32>(MISS);
    }
    return vec4<f32>(t, (o + d * t) / r);
}

fn nearer(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return select(a, b, b.x < a.x);
}

fn ray_cylinder(o: vec3<f32>, d: vec3<f32>, r: f32, h: f32, flags: u32, t_max: f32) -> vec4<f32> {
    let half = h * 0.5;
    var best = vec4<f32>(MISS);
    if (flags & FLAG_SIDE) != 0u {
        let a = d.x * d.x + d.z * d.z;
        if a > 0.0 {
            let b = o.x * d.x + o.z * d.z;
            let c = o.x * o.x + o.z * o.z - r * r;
            let disc = b * b - a * c;
            if disc >= 0.0 {
                let ts = roots(a, b, disc, c);
                for (var i = 0; i < 2; i++) {
                    let t = ts[i];
                    if t >= 0.0 && t <= t_max && finite(t) {
                        let p = o + d * t;
                        if abs(p.y) <= half {
                            best = nearer(best, vec4<f32>(t, p.x / r, 0.0, p.z / r));
                        }
                    }
                }
            }
        }
    }
    if d.y != 0.0 {
        if (flags & FLAG_TOP) != 0u {
            let t = (half - o.y) / d.y;
            let p = o + d * t;
            if t >= 0.0 && t <= t_max && p.x * p.x + p.z * p.z <= r * r {
                best = nearer(best, vec4<f32>(t, 0.0, 1.0, 0.0));
            }
        }
        if (flags & FLAG_BOTTOM) != 0u {
            let t = (-half - o.y) / d.y;
            let p = o + d * t;
            if t >= 0.0 && t <= t_max && p.x * p.x + p.z * p.z <= r * r {
                best = nearer(best, vec4<f32>(t, 0.0, -1.0, 0.0));
            }
        }
    }
    return best;
}

fn ray_cone(o: vec3<f32>, d: vec3<f32>, r: f32, h: f32, flags: u32, t_max: f32) -> vec4<f32> {
    let half = h * 0.5;
    var best = vec4<f32>(MISS);
    if (flags & FLAG_SIDE) != 0u {
        let k = r / h;
        let k2 = k * k;
        let yo = half - o.y;
        let a = d.x * d.x + d.z * d.z - k2 * d.y * d.y;
        let b = o.x * d.x + o.z * d.z + k2 * yo * d.y;
        let c = o.x * o.x + o.z * o.z - k2 * yo * yo;
        var ts = vec2<f32>(-1.0, -1.0);
        if abs(a) > 1.0e-30 {
            let disc = b * b - a * c;
            if disc >= 0.0 {
                let sq = sqrt(disc);
                ts = vec2<f32>((-b - sq) / a, (-b + sq) / a);
            }
        } else if b != 0.0 {
            ts.x = -c / (2.0 * b);
        }
        for (var i = 0; i < 2; i++) {
            let t = ts[i];
            if t >= 0.0 && t <= t_max && finite(t) {
                let p = o + d * t;
                if p.y >= -half && p.y <= half {
                    let radial_length = length(vec2<f32>(p.x, p.z));
                    var radial = vec3<f32>(0.0);
                    if radial_length > 0.0 {
                        radial = vec3<f32>(p.x, 0.0, p.z) / radial_length;
                    }
                    let normal = normalize(radial * h + vec3<f32>(0.0, r, 0.0));
                    best = nearer(best, vec4<f32>(t, normal));
                }
            }
        }
    }
    if (flags & FLAG_BOTTOM) != 0u && d.y != 0.0 {
        let t = (-half - o.y) / d.y;
        let p = o + d * t;
        if t >= 0.0 && t <= t_max && p.x * p.x + p.z * p.z <= r * r {
            best = nearer(best, vec4<f32>(t, 0.0, -1.0, 0.0));
        }
    }
    return best;
}

fn ray_triangle(o: vec3<f32>, d: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, t_max: f32) -> vec4<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let p = cross(d, e2);
    let det = dot(e1, p);
    if abs(det) < 1.0e-30 {
        return vec4<f32>(MISS);
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = dot(s, p) * inv;
    if u < 0.0 || u > 1.0 {
        return vec4<f32>(MISS);
    }
    let q = cross(s, e1);
    let v = dot(d, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return vec4<f32>(MISS);
    }
    let t = dot(e2, q) * inv;
    if t < 0.0 || t > t_max {
        return vec4<f32>(MISS);
    }
    var normal = normalize(cross(e1, e2));
    if dot(normal, d) > 0.0 {
        normal = -normal;
    }
    return vec4<f32>(t, normal);
}

fn box_interval(o: vec3<f32>, d: vec3<f32>, bmin: vec3<f32>, bmax: vec3<f32>, t_max: f32) -> bool {
    let inv = safe_recip(d);
    let t0 = (bmin - o) * inv;
    let t1 = (bmax - o) * inv;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let enter = max(max(near.x, near.y), max(near.z, 0.0));
    let exit = min(min(far.x, far.y), min(far.z, t_max));
    return enter <= exit;
}

struct Hit {
    t: f32,
    normal: vec3<f32>,
    prim: u32,
    color: vec4<f32>,
}

struct Placed {
    origin: vec3<f32>,
    direction: vec3<f32>,
    rotation: vec2<f32>, // cos, sin of the owner's heading (1, 0 for static)
}

// The ray in the primitive owner's frame (world for static parts, the robot for its own).
fn place(o: vec3<f32>, d: vec3<f32>, owner: u32, instance: vec4<u32>) -> Placed {
    if owner == STATIC_OWNER {
        return Placed(o, d, vec2<f32>(1.0, 0.0));
    }
    let base = (instance.y + owner) * 2u;
    let at = poses[base].xyz;
    let cs = poses[base + 1u].xy;
    let rel = o - at;
    let origin = vec3<f32>(cs.x * rel.x - cs.y * rel.z, rel.y, cs.y * rel.x + cs.x * rel.z);
    let direction = vec3<f32>(cs.x * d.x - cs.y * d.z, d.y, cs.y * d.x + cs.x * d.z);
    return Placed(origin, direction, cs);
}

fn unrotate(n: vec3<f32>, cs: vec2<f32>) -> vec3<f32> {
    return vec3<f32>(cs.x * n.x + cs.y * n.z, n.y, -cs.y * n.x + cs.x * n.z);
}

fn visible(pr: Prim, viewer: u32, instance: vec4<u32>) -> bool {
    let owner = pr.info.w;
    if owner == STATIC_OWNER {
        return (pr.info.y & FLAG_VISIBLE) != 0u;
    }
    if owner >= instance.z {
        return false;
    }
    if owner == viewer {
        return (pr.info.y & FLAG_OWN_VISIBLE) != 0u;
    }
    return (pr.info.y & FLAG_VISIBLE) != 0u;
}

// The nearest visible surface within t_max (prim = 0xffffffff when none).
fn trace(o: vec3<f32>, d: vec3<f32>, t_max: f32, viewer: u32, instance: vec4<u32>) -> Hit {
    let scene = scenes[instance.x];
    var best = Hit(t_max, vec3<f32>(0.0), 0xffffffffu, vec4<f32>(0.0));
    let first = scene.ranges.x;
    for (var index = first; index < first + scene.ranges.y; index++) {
        let pr = prims[index];
        if !visible(pr, viewer, instance) {
            continue;
        }
        let placed = place(o, d, pr.info.w, instance);
        if !box_interval(placed.origin, placed.direction, pr.bmin.xyz, pr.bmax.xyz, best.t) {
            continue;
        }
        let lo = vec3<f32>(
            dot(pr.inv0.xyz, placed.origin) + pr.inv0.w,
            dot(pr.inv1.xyz, placed.origin) + pr.inv1.w,
            dot(pr.inv2.xyz, placed.origin) + pr.inv2.w,
        );
        let ld = vec3<f32>(
            dot(pr.inv0.xyz, placed.direction),
            dot(pr.inv1.xyz, placed.direction),
            dot(pr.inv2.xyz, placed.direction),
        );
        var hit = vec4<f32>(MISS);
        var color = vec4<f32>(0.0);
        switch pr.info.x {
            case KIND_BOX: {
                hit = ray_box(lo, ld, pr.params.xyz, best.t);
            }
            case KIND_CYLINDER: {
                hit = ray_cylinder(lo, ld, pr.params.x, pr.params.y, pr.info.y, best.t);
            }
            case KIND_CONE: {
                hit = ray_cone(lo, ld, pr.params.x, pr.params.y, pr.info.y, best.t);
            }
            case KIND_SPHERE: {
                hit = ray_sphere(lo, ld, pr.params.x, best.t);
            }
            default: {
                for (var tri = pr.mesh.x; tri < pr.mesh.x + pr.mesh.y; tri++) {
                    let found = ray_triangle(
                        lo,
                        ld,
                        triangles[tri * 4u].xyz,
                        triangles[tri * 4u + 1u].xyz,
                        triangles[tri * 4u + 2u].xyz,
                        min(hit.x, best.t),
                    );
                    if found.x < hit.x {
                        hit = found;
                        color = triangles[tri * 4u + 3u];
                    }
                }
            }
        }
        if hit.x < best.t || (hit.x <= best.t && best.prim == 0xffffffffu && hit.x < MISS) {
            // Inverse transpose of the primitive's frame, then the owner's rotation.
            let n = hit.yzw;
            let local_normal = n.x * pr.inv0.xyz + n.y * pr.inv1.xyz + n.z * pr.inv2.xyz;
            let length_n = length(local_normal);
            var normal = vec3<f32>(0.0);
            if length_n > 0.0 {
                normal = unrotate(local_normal / length_n, placed.rotation);
            }
            best = Hit(hit.x, normal, index, color);
        }
    }
    return best;
}

fn light_world(light: Light, instance: vec4<u32>) -> Light {
    var placed = light;
    let owner = light.info.y;
    if owner != STATIC_OWNER && owner < instance.z {
        let base = (instance.y + owner) * 2u;
        let at = poses[base].xyz;
        let cs = poses[base + 1u].xy;
        placed.location = vec4<f32>(unrotate(light.location.xyz, cs) + at, light.location.w);
        placed.direction = vec4<f32>(unrotate(light.direction.xyz, cs), light.direction.w);
    }
    return placed;
}

fn attenuate(coefficients: vec3<f32>, distance: f32) -> f32 {
    return 1.0 / max(coefficients.x + coefficients.y * distance + coefficients.z * distance * distance, 1.0);
}

// Direction towards the light and attenuation × spot factor; w < 0 beyond the radius.
fn light_at(light: Light, point: vec3<f32>) -> vec4<f32> {
    let kind = light.info.x;
    if kind == 0u {
        return vec4<f32>(-light.direction.xyz, 1.0);
    }
    let offset = light.location.xyz - point;
    let distance = length(offset);
    if distance > light.location.w {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let to_light = offset / max(distance, 1.0e-30);
    var factor = attenuate(light.attenuation.xyz, distance);
    if kind == 2u {
        let angle = acos(clamp(dot(-to_light, light.direction.xyz), -1.0, 1.0));
        let beam = light.attenuation.w;
        let cut_off = light.spot.x;
        var spot = 1.0;
        if angle >= cut_off {
            spot = 0.0;
        } else if angle > beam {
            spot = (angle - cut_off) / (beam - cut_off);
        }
        factor = factor * spot;
    }
    return vec4<f32>(to_light, factor);
}

fn occluded(point: vec3<f32>, light: Light, viewer: u32, instance: vec4<u32>) -> bool {
    var direction = -light.direction.xyz;
    var limit = MISS;
    if light.info.x != 0u {
        direction = light.location.xyz - point;
        limit = 1.0 - 1.0e-4;
    }
    let unit = normalize(direction);
    let hit = trace(point + unit * SHADOW_OFFSET, direction, limit, viewer, instance);
    return hit.prim != 0xffffffffu;
}

fn shade(hit: Hit, eye: vec3<f32>, direction: vec3<f32>, viewer: u32, instance: vec4<u32>) -> vec3<f32> {
    let material = materials[prims[hit.prim].info.z];
    var diffuse = material.diffuse.xyz;
    if hit.color.w > 0.0 {
        diffuse = hit.color.xyz;
    }
    if material.emissive.w > 0.0 {
        return select(material.emissive.xyz, hit.color.xyz, hit.color.w > 0.0);
    }
    let point = eye + direction * hit.t;
    var out = material.emissive.xyz;
    let to_eye = eye - point;
    var view = vec3<f32>(0.0);
    if length(to_eye) > 0.0 {
        view = normalize(to_eye);
    }
    var normal = hit.normal;
    if dot(normal, view) < 0.0 {
        normal = -normal;
    }
    let scene = scenes[instance.x];
    let has_specular = any(material.specular.xyz > vec3<f32>(0.0));
    for (var index = scene.ranges.z; index < scene.ranges.z + scene.ranges.w; index++) {
        let light = light_world(lights[index], instance);
        let reach = light_at(light, point);
        if reach.w <= 0.0 {
            continue;
        }
        let to_light = reach.xyz;
        let n_dot_l = max(dot(normal, to_light), 0.0);
        var specular_factor = 0.0;
        if n_dot_l > 0.0 && has_specular {
            let sum = to_light + view;
            if length(sum) > 0.0 {
                specular_factor = pow(max(dot(normal, normalize(sum)), 0.0), material.specular.w * 128.0);
            }
        }
        let lit = n_dot_l > 0.0 && !(light.info.z != 0u && occluded(point, light, viewer, instance));
        let ambient = light.direction.w * diffuse * material.diffuse.w;
        var direct = vec3<f32>(0.0);
        if lit {
            direct = light.color.w * (diffuse * n_dot_l + material.specular.xyz * specular_factor);
        }
        out += reach.w * light.color.xyz * (ambient + direct);
    }
    return out;
}

fn radiance(eye: vec3<f32>, direction: vec3<f32>, viewer: u32, instance: vec4<u32>) -> vec3<f32> {
    let hit = trace(eye, direction, MISS, viewer, instance);
    if hit.prim == 0xffffffffu {
        let scene = scenes[instance.x];
        if scene.ground.w > 0.0 && direction.y < 0.0 {
            return scene.ground.xyz;
        }
        return scene.sky.xyz;
    }
    return shade(hit, eye, direction, viewer, instance);
}

fn luminance(rgb: vec3<f32>) -> f32 {
    return 0.299 * rgb.x + 0.587 * rgb.y + 0.114 * rgb.z;
}

fn quantize(rgb: vec3<f32>) -> vec3<f32> {
    // floor(x + ½): the CPU's round half away from zero, for x ≥ 0.
    return floor(clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0)) * 255.0 + 0.5) / 255.0;
}

fn view_index(group: vec3<u32>) -> u32 {
    return group.y + group.z * 65535u;
}

@compute @workgroup_size(64)
fn trace_views(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    let v = view_index(group);
    if v >= batch.x {
        return;
    }
    let view = views[v];
    let pixel = id.x;
    if pixel >= view.b.x {
        return;
    }
    let instance = instances[view.a.x];
    let viewer = view.a.y;
    let n = view.b.y;
    let eye = view.eye.xyz;
    let heading = view.eye.w;
    if view.a.z == 0u {
        let column = pixel % FLAT_COLUMNS;
        let row = pixel / FLAT_COLUMNS;
        var sum = vec3<f32>(0.0);
        for (var si = 0u; si < n; si++) {
            let entry = view.c.x + (column * n + si) * 2u;
            let world = heading + view.geo.x + tables[entry];
            let inv_slant = tables[entry + 1u];
            let horizontal = vec2<f32>(cos(world), -sin(world));
            for (var sj = 0u; sj < n; sj++) {
                let tan_elevation = tables[view.c.y + row * n + sj] * inv_slant;
                let direction = vec3<f32>(horizontal.x, tan_elevation, horizontal.y);
                sum += radiance(eye, direction, viewer, instance);
            }
        }
        var rgb = sum / f32(n * n);
        if view.b.z != 0u {
            rgb = quantize(rgb);
        }
        flat[view.b.w + pixel] = luminance(rgb);
    } else {
        let center = view.geo.x - (f32(pixel) + 0.5) * view.geo.y;
        var sum = 0.0;
        for (var i = 0u; i < n; i++) {
            let alpha = center + ((f32(i) + 0.5) / f32(n) - 0.5) * view.geo.y;
            let world = heading + alpha;
            let cw = cos(world);
            let sw = sin(world);
            for (var j = 0u; j < n; j++) {
                let phi = ((f32(j) + 0.5) / f32(n) * 2.0 - 1.0) * view.geo.z;
                let cp = cos(phi);
                let direction = vec3<f32>(cw * cp, sin(phi), -sw * cp);
                sum += luminance(radiance(eye, direction, viewer, instance));
            }
        }
        outputs[view.a.w + pixel] = sum / f32(n * n);
    }
}

fn flat_at(base: u32, column: u32, row: u32) -> f32 {
    return flat[base + row * FLAT_COLUMNS + column];
}

@compute @workgroup_size(64)
fn warp_views(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    let v = view_index(group);
    if v >= batch.x {
        return;
    }
    let view = views[v];
    let j = id.x;
    if view.a.z != 0u || j >= FLAT_COLUMNS {
        return;
    }
    let base = view.b.w;
    var sum = 0.0;
    for (var k = 0u; k < FLAT_ROWS; k++) {
        let entry = batch.y + ((view.c.z * FLAT_COLUMNS + j) * FLAT_ROWS + k) * 2u;
        let u = clamp(tables[entry], 0.0, f32(FLAT_COLUMNS - 1u));
        let w = clamp(tables[entry + 1u], 0.0, f32(FLAT_ROWS - 1u));
        let c0 = u32(floor(u));
        let r0 = u32(floor(w));
        let c1 = min(c0 + 1u, FLAT_COLUMNS - 1u);
        let r1 = min(r0 + 1u, FLAT_ROWS - 1u);
        let fu = u - f32(c0);
        let fw = w - f32(r0);
        sum += (flat_at(base, c0, r0) * (1.0 - fu) + flat_at(base, c1, r0) * fu) * (1.0 - fw)
            + (flat_at(base, c0, r1) * (1.0 - fu) + flat_at(base, c1, r1) * fu) * fw;
    }
    outputs[view.a.w + j] = sum / f32(FLAT_ROWS);
}
