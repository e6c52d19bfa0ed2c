//! The render graph: a flat, backend-neutral description of what can be seen. The CPU
//! renderer, the wgpu backend and the glTF exporter all read it; none of their details live
//! here.
//!
//! Box, Cylinder, Cone and Sphere stay analytic; IndexedFaceSet, ElevationGrid, Extrusion,
//! Plane, Capsule and mesh files are triangulated (concave and non-planar faces included).
//! Lines and points, which no renderer draws, are kept apart for exporters. Static parts are kept apart from
//! robot-attached parts (whose frames are relative to their robot) and indexed by a BVH.

use glam::{DVec2, DVec3};
use regatta_schema::NodeId;

use crate::geometry::{Aabb, Bvh, Footprint, Frame};

/// Handle of a primitive in [`RenderGraph::primitives`].
pub type PrimitiveId = usize;

/// Handle of a group in [`RenderGraph::groups`].
pub type GroupId = usize;

/// Analytic or triangulated geometry, in the primitive's local frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Box {
        half: DVec3,
    },
    Cylinder {
        radius: f64,
        height: f64,
        side: bool,
        bottom: bool,
        top: bool,
    },
    Cone {
        radius: f64,
        height: f64,
        side: bool,
        bottom: bool,
    },
    Sphere {
        radius: f64,
    },
    /// Index into [`RenderGraph::meshes`].
    Mesh(usize),
}

impl Shape {
    /// Bounds in the local frame.
    pub fn local_bounds(&self, meshes: &[Mesh]) -> Aabb {
        match self {
            Shape::Box { half } => Aabb {
                min: -*half,
                max: *half,
            },
            Shape::Cylinder { radius, height, .. } | Shape::Cone { radius, height, .. } => {
                let half = DVec3::new(*radius, height / 2.0, *radius);
                Aabb {
                    min: -half,
                    max: half,
                }
            }
            Shape::Sphere { radius } => Aabb {
                min: DVec3::splat(-radius),
                max: DVec3::splat(*radius),
            },
            Shape::Mesh(index) => Aabb::from_points(meshes[*index].used_positions()),
        }
    }

    /// Tight bounds of the shape placed by `frame` (exact for the analytic shapes under any
    /// affine frame, exact for meshes), so that culling and exported bounds agree.
    pub fn bounds_under(&self, frame: &Frame, meshes: &[Mesh]) -> Aabb {
        let center = frame.translation;
        let round = |radial_x: DVec3, radial_z: DVec3| {
            DVec3::new(
                libm::hypot(radial_x.x, radial_z.x),
                libm::hypot(radial_x.y, radial_z.y),
                libm::hypot(radial_x.z, radial_z.z),
            )
        };
        match self {
            Shape::Box { .. } => self.local_bounds(meshes).transformed(frame),
            Shape::Cylinder { radius, height, .. } => {
                let axis = frame.apply_vector(DVec3::Y * (height / 2.0)).abs();
                let disk = round(
                    frame.apply_vector(DVec3::X * *radius),
                    frame.apply_vector(DVec3::Z * *radius),
                );
                Aabb {
                    min: center - axis - disk,
                    max: center + axis + disk,
                }
            }
            Shape::Cone { radius, height, .. } => {
                let axis = frame.apply_vector(DVec3::Y * (height / 2.0));
                let disk = round(
                    frame.apply_vector(DVec3::X * *radius),
                    frame.apply_vector(DVec3::Z * *radius),
                );
                let (apex, base) = (center + axis, center - axis);
                Aabb {
                    min: apex.min(base - disk),
                    max: apex.max(base + disk),
                }
            }
            Shape::Sphere { radius } => {
                let l = frame.linear;
                let extent =
                    DVec3::new(l.row(0).length(), l.row(1).length(), l.row(2).length()) * *radius;
                Aabb {
                    min: center - extent,
                    max: center + extent,
                }
            }
            Shape::Mesh(index) => {
                Aabb::from_points(meshes[*index].used_positions().map(|p| frame.apply(p)))
            }
        }
    }

    /// The horizontal cross-section and half height under `frame`, for boxes and cylinders
    /// (meaningful when the frame keeps them upright).
    pub fn footprint(&self, frame: &Frame) -> Option<(Footprint, f64)> {
        let center = DVec2::new(frame.translation.x, frame.translation.z);
        let x = frame.apply_vector(DVec3::X);
        let y = frame.apply_vector(DVec3::Y);
        let z = frame.apply_vector(DVec3::Z);
        match self {
            Shape::Box { half } => {
                let (u, v) = (DVec2::new(x.x, x.z), DVec2::new(z.x, z.z));
                Some((
                    Footprint::Rect {
                        center,
                        u: u.normalize(),
                        v: v.normalize(),
                        half_u: half.x * u.length(),
                        half_v: half.z * v.length(),
                    },
                    half.y * y.length(),
                ))
            }
            Shape::Cylinder { radius, height, .. } => Some((
                Footprint::Circle {
                    center,
                    radius: radius * DVec2::new(x.x, x.z).length(),
                },
                height / 2.0 * y.length(),
            )),
            _ => None,
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            Shape::Box { .. } => "Box",
            Shape::Cylinder { .. } => "Cylinder",
            Shape::Cone { .. } => "Cone",
            Shape::Sphere { .. } => "Sphere",
            Shape::Mesh(_) => "Mesh",
        }
    }
}

/// A triangle mesh with optional per-triangle colours (from Color nodes).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    pub triangle_colors: Option<Vec<[f64; 3]>>,
    /// Per-corner colours, parallel to `triangles`, when the file gives colours per vertex
    /// (the renderers use the per-triangle average; exporters keep the gradient).
    pub corner_colors: Option<Vec<[[f64; 3]; 3]>>,
    /// Whether back faces are culled (`solid TRUE`).
    pub solid: bool,
    pub crease_angle: f64,
    /// Per-corner texture coordinates (s, t), parallel to `triangles`, when the file gives
    /// them or its node defines them (a grid, a plane); exporters generate the others.
    pub tex_coords: Option<Vec<[[f64; 2]; 3]>>,
}

impl Mesh {
    /// Sets per-corner texture coordinates from one (s, t) per position.
    pub fn tex_coords_per_point(&mut self, points: &[[f64; 2]]) {
        let at = |i: u32| points.get(i as usize).copied().unwrap_or([0.0; 2]);
        self.tex_coords = Some(self.triangles.iter().map(|t| t.map(at)).collect());
    }

    /// The positions triangles refer to (points no face uses are not geometry), with repeats.
    pub fn used_positions(&self) -> impl Iterator<Item = DVec3> + '_ {
        self.triangles
            .iter()
            .flatten()
            .map(|&i| self.positions[i as usize])
    }
}

/// An image a texture shows, as the file holds it (PNG or JPEG), or converted to PNG (a
/// PixelTexture, or another format the `image` crate reads).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// The url, or "PixelTexture".
    pub name: String,
    pub mime: &'static str,
    pub bytes: std::sync::Arc<[u8]>,
    pub repeat_s: bool,
    pub repeat_t: bool,
}

/// VRML97's TextureTransform: texture coordinates are translated, then turned and scaled
/// about `center`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureTransform {
    pub center: [f64; 2],
    pub rotation: f64,
    pub scale: [f64; 2],
    pub translation: [f64; 2],
}

/// The images a material maps (indices into [`RenderGraph::textures`]) and Webots' PBR
/// parameters. Only exporters read them; the renderers use the material's colours.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Maps {
    pub base_color: Option<usize>,
    /// A PBRAppearance's roughness and metalness maps combined as glTF wants them (roughness
    /// in green, metalness in blue).
    pub metallic_roughness: Option<usize>,
    pub normal: Option<usize>,
    pub occlusion: Option<usize>,
    pub emissive: Option<usize>,
    pub transform: Option<TextureTransform>,
    /// A PBRAppearance's (roughness, metalness), kept as written.
    pub pbr: Option<(f64, f64)>,
}

impl Maps {
    pub const NONE: Maps = Maps {
        base_color: None,
        metallic_roughness: None,
        normal: None,
        occlusion: None,
        emissive: None,
        transform: None,
        pbr: None,
    };

    /// Whether any image is mapped.
    pub fn textured(&self) -> bool {
        self.base_color.is_some()
            || self.metallic_roughness.is_some()
            || self.normal.is_some()
            || self.occlusion.is_some()
            || self.emissive.is_some()
    }
}

/// VRML97 Material, plus infra-red reflectance. `unlit` is VRML's "no material": colour 1, no
/// lighting.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub diffuse: [f64; 3],
    pub ambient_intensity: f64,
    pub specular: [f64; 3],
    pub emissive: [f64; 3],
    pub shininess: f64,
    pub transparency: f64,
    pub ir_reflectance: f64,
    pub unlit: bool,
    /// Textures and PBR parameters, for exporters.
    pub maps: Maps,
}

impl Material {
    pub const UNLIT: Material = Material {
        diffuse: [1.0; 3],
        ambient_intensity: 0.0,
        specular: [0.0; 3],
        emissive: [1.0; 3],
        shininess: 0.0,
        transparency: 0.0,
        ir_reflectance: 1.0,
        unlit: true,
        maps: Maps::NONE,
    };

    /// A white VRML97 Material otherwise at its defaults: what a texture without a Material,
    /// or a mesh file's own colours, is lit as.
    pub const WHITE: Material = Material {
        diffuse: [1.0; 3],
        ambient_intensity: 0.2,
        specular: [0.0; 3],
        emissive: [0.0; 3],
        shininess: 0.2,
        transparency: 0.0,
        ir_reflectance: 1.0,
        unlit: false,
        maps: Maps::NONE,
    };
}

/// Lines or points (IndexedLineSet, PointSet): exported, never drawn by the simulator's
/// renderers (VRML97 lines and points have no area to see).
#[derive(Clone, Debug, PartialEq)]
pub struct LineSet {
    /// In the frame below; for lines, two per segment.
    pub positions: Vec<DVec3>,
    /// Whether `positions` are segment ends in pairs (else points).
    pub lines: bool,
    /// One colour per position, when the file gives colours.
    pub colors: Option<Vec<[f64; 3]>>,
    pub frame: Frame,
    pub material: usize,
    pub owner: Owner,
    /// The Shape node it comes from.
    pub node: NodeId,
    pub group: Option<GroupId>,
}

/// A Shape whose geometry is not in the graph, and why (for `regatta gltf --report`).
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    /// The Shape (or CadShape) node.
    pub node: NodeId,
    /// Its geometry's type, or "" when it has none.
    pub geometry: String,
    pub reason: String,
}

/// Who a primitive or light moves with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Owner {
    Static,
    /// Index into the sensor rig's robots; the frame is relative to the robot.
    Robot(usize),
}

/// One drawable thing.
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    pub shape: Shape,
    pub frame: Frame,
    pub inverse: Frame,
    pub material: usize,
    pub owner: Owner,
    /// The Shape node it comes from.
    pub node: NodeId,
    /// Bounds in the frame of its owner (world for static parts, robot for attached ones).
    pub bounds: Aabb,
    /// The grouping node it sits in, for exporters that keep the hierarchy.
    pub group: Option<GroupId>,
    /// Rotated only about the vertical axis (cylinder and cone axes vertical, boxes
    /// yaw-rotated) with circular cross-sections: what the column renderer handles.
    pub upright: bool,
}

/// The light kinds of VRML97.
#[derive(Clone, Debug, PartialEq)]
pub enum LightKind {
    Directional {
        direction: DVec3,
    },
    Point {
        location: DVec3,
        radius: f64,
        attenuation: DVec3,
    },
    Spot {
        location: DVec3,
        direction: DVec3,
        radius: f64,
        attenuation: DVec3,
        beam_width: f64,
        cut_off: f64,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub kind: LightKind,
    pub color: [f64; 3],
    pub intensity: f64,
    pub ambient_intensity: f64,
    pub on: bool,
    pub shadows: bool,
    pub owner: Owner,
    pub node: NodeId,
    pub group: Option<GroupId>,
}

/// A grouping node of the file (Transform, Solid, Group, a robot…), kept so that exporters can
/// rebuild the hierarchy; the renderers never read it.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// The DEF name, else the PROTO instance's name, else the node's `name` field, else its type.
    pub name: String,
    pub parent: Option<GroupId>,
    /// The frame its children are placed in, in its owner's coordinates (world for static
    /// groups, the robot's frame for robot-attached ones). A robot's own group is static and
    /// sits at the robot's start pose.
    pub frame: Frame,
    pub owner: Owner,
    pub node: NodeId,
    /// For a robot's own group: its index in the sensor rig.
    pub robot: Option<usize>,
}

/// The first Viewpoint of the file: where a viewer's camera starts.
#[derive(Clone, Debug, PartialEq)]
pub struct Viewpoint {
    pub name: String,
    /// World frame; the camera looks along its −z with +y up.
    pub frame: Frame,
    /// Radians, across the smaller image dimension (VRML97).
    pub field_of_view: f64,
}

/// What is seen where no geometry is.
#[derive(Clone, Debug, PartialEq)]
pub struct Background {
    pub sky: [f64; 3],
    /// Below the horizon, if the world gives ground colours.
    pub ground: Option<[f64; 3]>,
}

/// The compiled scene.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderGraph {
    pub primitives: Vec<Primitive>,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    /// Lines and points, for exporters.
    pub lines: Vec<LineSet>,
    /// The images materials map, each file once.
    pub textures: Vec<Texture>,
    /// Shapes left out, with the reason, for exporters' reports.
    pub skipped: Vec<Skipped>,
    pub groups: Vec<Group>,
    pub viewpoint: Option<Viewpoint>,
    pub background: Background,
    /// The static primitives, in the order [`RenderGraph::static_index`] refers to.
    pub static_primitives: Vec<PrimitiveId>,
    pub static_index: Bvh,
}

impl RenderGraph {
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }

    /// Bounds of all static geometry.
    pub fn static_bounds(&self) -> Aabb {
        self.static_primitives
            .iter()
            .fold(Aabb::EMPTY, |b, &p| b.union(self.primitives[p].bounds))
    }
}

/// Builds the static BVH over the graph's static primitives.
pub(crate) fn index_static(graph: &mut RenderGraph) {
    graph.static_primitives = (0..graph.primitives.len())
        .filter(|&p| graph.primitives[p].owner == Owner::Static)
        .collect();
    let boxes: Vec<Aabb> = graph
        .static_primitives
        .iter()
        .map(|&p| graph.primitives[p].bounds)
        .collect();
    graph.static_index = Bvh::build(&boxes);
}
