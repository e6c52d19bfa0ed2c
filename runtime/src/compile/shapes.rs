//! The scene's nodes read into the render graph's parts: a Shape's geometry into a [`Shape`]
//! (IndexedFaceSet and ElevationGrid triangulated into meshes by [`super::triangulate`],
//! Plane, Capsule, Extrusion and Webots' grids by [`super::solids`], mesh files decoded by
//! [`super::meshfile`]) or a [`LineSet`], or the reason it is left out; its
//! appearance into a [`Material`] (VRML97 Material or PBRAppearance), and the first
//! Background into the graph's [`Background`].

use glam::DVec3;
use regatta_schema::{NodeId, Scene, Value};

use super::graph::{Background, LineSet, Material, Mesh, Shape};
use super::{meshfile, solids, triangulate};

/// Reads a Material node (or its absence) into a [`Material`].
pub(crate) fn material_of(scene: &Scene, appearance: Option<NodeId>) -> Material {
    if let Some(pbr) = appearance.filter(|&a| scene.type_name(a) == "PBRAppearance") {
        return pbr_material(scene, pbr);
    }
    let Some(material) = appearance.and_then(|a| scene.child(a, "material")) else {
        return Material::UNLIT;
    };
    Material {
        diffuse: scene.vec3(material, "diffuseColor"),
        ambient_intensity: scene.float(material, "ambientIntensity"),
        specular: scene.vec3(material, "specularColor"),
        emissive: scene.vec3(material, "emissiveColor"),
        shininess: scene.float(material, "shininess"),
        transparency: scene.float(material, "transparency"),
        ir_reflectance: scene.float(material, "irReflectance"),
        unlit: false,
        maps: super::graph::Maps::NONE,
    }
}

/// Webots' PBRAppearance as a VRML material (the catalogue's PBRAppearance doc): the base
/// colour is diffuse, the emission scaled by its intensity, the surface as shiny as it is
/// smooth but without specular colour, and its infra-red reflectance is the base colour's red
/// component, since Webots' infra-red distance sensors respond to red.
fn pbr_material(scene: &Scene, pbr: NodeId) -> Material {
    let base = scene.vec3(pbr, "baseColor");
    let emissive = scene.vec3(pbr, "emissiveColor");
    let intensity = scene.float(pbr, "emissiveIntensity");
    Material {
        diffuse: base,
        ambient_intensity: 0.2,
        specular: [0.0; 3],
        emissive: emissive.map(|c| c * intensity),
        shininess: 1.0 - scene.float(pbr, "roughness"),
        transparency: scene.float(pbr, "transparency"),
        ir_reflectance: base[0],
        unlit: false,
        maps: super::graph::Maps::NONE,
    }
}

/// What a geometry node becomes.
pub enum Geometry {
    Shape(Shape),
    /// Lines or points; the compiler fills in the frame, material, owner and node.
    Lines(LineSet),
}

/// Reads a geometry node into a shape; meshes are triangulated into `meshes`. `Err` says why
/// there is nothing to draw.
pub(crate) fn shape_of(
    scene: &Scene,
    geometry: NodeId,
    meshes: &mut Vec<Mesh>,
) -> Result<Geometry, String> {
    let shape = match scene.type_name(geometry) {
        "Box" => {
            let size = scene.vec3(geometry, "size");
            Shape::Box {
                half: DVec3::from_array(size) * 0.5,
            }
        }
        "Cylinder" => Shape::Cylinder {
            radius: scene.float(geometry, "radius"),
            height: scene.float(geometry, "height"),
            side: scene.bool(geometry, "side"),
            bottom: scene.bool(geometry, "bottom"),
            top: scene.bool(geometry, "top"),
        },
        "Cone" => Shape::Cone {
            radius: scene.float(geometry, "bottomRadius"),
            height: scene.float(geometry, "height"),
            side: scene.bool(geometry, "side"),
            bottom: scene.bool(geometry, "bottom"),
        },
        "Sphere" => Shape::Sphere {
            radius: scene.float(geometry, "radius"),
        },
        "IndexedFaceSet" => mesh(triangulate::indexed_face_set(scene, geometry), meshes)?,
        "ElevationGrid" => {
            let webots = scene
                .spec(geometry)
                .field_index("yDimension")
                .is_some_and(|i| scene.node(geometry).written.get(i))
                && !scene
                    .spec(geometry)
                    .field_index("zDimension")
                    .is_some_and(|i| scene.node(geometry).written.get(i));
            mesh(
                if webots {
                    solids::webots_elevation_grid(scene, geometry)
                } else {
                    triangulate::elevation_grid(scene, geometry)
                },
                meshes,
            )?
        }
        "Extrusion" => mesh(solids::extrusion(scene, geometry), meshes)?,
        "Plane" => mesh(solids::plane(scene, geometry), meshes)?,
        "Capsule" => mesh(solids::capsule(scene, geometry), meshes)?,
        "Mesh" => {
            let asset = mesh_asset(scene, geometry)?;
            let file = meshfile::decode(asset, scene.bool(geometry, "ccw"))?;
            // The Shape's appearance colours a Mesh; the file's materials do not.
            mesh(file.mesh, meshes)?
        }
        "IndexedLineSet" => return line_set(scene, geometry).map(Geometry::Lines),
        "PointSet" => return point_set(scene, geometry).map(Geometry::Lines),
        other => return Err(format!("{other} is not a geometry regatta reads")),
    };
    Ok(Geometry::Shape(shape))
}

/// A mesh into the graph's meshes; `Err` when it has no triangle.
fn mesh(mesh: Mesh, meshes: &mut Vec<Mesh>) -> Result<Shape, String> {
    if mesh.triangles.is_empty() {
        return Err("its geometry has no triangle".to_owned());
    }
    meshes.push(mesh);
    Ok(Shape::Mesh(meshes.len() - 1))
}

/// The file a Mesh or CadShape names, as the check read it.
fn mesh_asset(scene: &Scene, node: NodeId) -> Result<&regatta_schema::Asset, String> {
    scene
        .asset(node)
        .ok_or_else(|| match scene.strings(node, "url").first() {
            Some(url) => format!("its file '{url}' could not be read (the check said why)"),
            None => "it names no file".to_owned(),
        })
}

/// Webots' CadShape: its file's mesh, coloured by the file's materials.
pub(crate) fn cad_shape(
    scene: &Scene,
    node: NodeId,
    meshes: &mut Vec<Mesh>,
) -> Result<Shape, String> {
    let asset = mesh_asset(scene, node)?;
    let file = meshfile::decode(asset, scene.bool(node, "ccw"))?;
    let mut m = file.mesh;
    m.triangle_colors = file.colors;
    mesh(m, meshes)
}

fn points_of(scene: &Scene, node: NodeId) -> &[[f64; 3]] {
    match scene.child(node, "coord").map(|c| scene.field(c, "point")) {
        Some(Value::Vec3s(points)) => points,
        _ => &[],
    }
}

fn colors_of(scene: &Scene, node: NodeId) -> &[[f64; 3]] {
    match scene.child(node, "color").map(|c| scene.field(c, "color")) {
        Some(Value::Vec3s(colors)) => colors,
        _ => &[],
    }
}

fn empty_lines(lines: bool) -> LineSet {
    LineSet {
        positions: Vec::new(),
        lines,
        colors: None,
        frame: crate::geometry::Frame::IDENTITY,
        material: 0,
        owner: super::graph::Owner::Static,
        node: NodeId(0),
        group: None,
    }
}

/// VRML97's IndexedLineSet as segments, colours per vertex or per polyline (VRML97 6.24).
fn line_set(scene: &Scene, node: NodeId) -> Result<LineSet, String> {
    let points = points_of(scene, node);
    let colors = colors_of(scene, node);
    let ints = |name| match scene.field(node, name) {
        Value::Ints(v) => v.as_slice(),
        _ => &[],
    };
    let (index, color_index) = (ints("coordIndex"), ints("colorIndex"));
    let per_vertex = scene.bool(node, "colorPerVertex");
    let mut set = empty_lines(true);
    let mut out_colors = Vec::new();
    let color = |k: usize, polyline: usize| -> Option<[f64; 3]> {
        let i = if per_vertex {
            if color_index.is_empty() {
                index.get(k).copied()
            } else {
                color_index.get(k).copied()
            }
        } else if color_index.is_empty() {
            Some(polyline as i32)
        } else {
            color_index.get(polyline).copied()
        }?;
        usize::try_from(i).ok().and_then(|i| colors.get(i)).copied()
    };
    let mut polyline = 0;
    for k in 0..index.len() {
        if index[k] < 0 {
            polyline += 1;
            continue;
        }
        let Some(&next) = index.get(k + 1).filter(|&&n| n >= 0) else {
            continue;
        };
        let (a, b) = (index[k] as usize, next as usize);
        if a >= points.len() || b >= points.len() {
            continue;
        }
        set.positions.push(DVec3::from_array(points[a]));
        set.positions.push(DVec3::from_array(points[b]));
        out_colors.push(color(k, polyline).unwrap_or([1.0; 3]));
        out_colors.push(color(k + 1, polyline).unwrap_or([1.0; 3]));
    }
    if set.positions.is_empty() {
        return Err("its IndexedLineSet has no segment".to_owned());
    }
    set.colors = (!colors.is_empty()).then_some(out_colors);
    Ok(set)
}

/// VRML97's PointSet: one colour per point when there are enough.
fn point_set(scene: &Scene, node: NodeId) -> Result<LineSet, String> {
    let points = points_of(scene, node);
    let colors = colors_of(scene, node);
    if points.is_empty() {
        return Err("its PointSet has no point".to_owned());
    }
    let mut set = empty_lines(false);
    set.positions = points.iter().map(|p| DVec3::from_array(*p)).collect();
    set.colors = (colors.len() >= points.len()).then(|| colors[..points.len()].to_vec());
    Ok(set)
}

/// Background from the first Background node (sky colour × luminosity).
pub(crate) fn background_of(scene: &Scene) -> Background {
    let Some(&node) = scene.find("Background").first() else {
        return Background {
            sky: [0.0; 3],
            ground: None,
        };
    };
    let luminosity = scene.float(node, "luminosity");
    let first = |name: &str| match scene.field(node, name) {
        Value::Vec3s(colors) => colors.first().map(|c| c.map(|x| x * luminosity)),
        _ => None,
    };
    Background {
        sky: first("skyColor").unwrap_or([0.0; 3]),
        ground: first("groundColor"),
    }
}
