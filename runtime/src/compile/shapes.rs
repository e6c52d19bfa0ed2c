//! The scene's nodes read into the render graph's parts: a Shape's geometry into a [`Shape`]
//! (IndexedFaceSet and ElevationGrid triangulated into meshes by [`super::triangulate`]), its
//! appearance into a [`Material`] (VRML97 Material or PBRAppearance), and the first
//! Background into the graph's [`Background`].

use glam::DVec3;
use regatta_schema::{NodeId, Scene, Value};

use super::graph::{Background, Material, Mesh, Shape};
use super::triangulate;

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
    }
}

/// Reads a geometry node into a shape; meshes are triangulated into `meshes`. `None` for
/// geometry with nothing to draw.
pub(crate) fn shape_of(scene: &Scene, geometry: NodeId, meshes: &mut Vec<Mesh>) -> Option<Shape> {
    match scene.type_name(geometry) {
        "Box" => {
            let size = scene.vec3(geometry, "size");
            Some(Shape::Box {
                half: DVec3::from_array(size) * 0.5,
            })
        }
        "Cylinder" => Some(Shape::Cylinder {
            radius: scene.float(geometry, "radius"),
            height: scene.float(geometry, "height"),
            side: scene.bool(geometry, "side"),
            bottom: scene.bool(geometry, "bottom"),
            top: scene.bool(geometry, "top"),
        }),
        "Cone" => Some(Shape::Cone {
            radius: scene.float(geometry, "bottomRadius"),
            height: scene.float(geometry, "height"),
            side: scene.bool(geometry, "side"),
            bottom: scene.bool(geometry, "bottom"),
        }),
        "Sphere" => Some(Shape::Sphere {
            radius: scene.float(geometry, "radius"),
        }),
        "IndexedFaceSet" => {
            let mesh = triangulate::indexed_face_set(scene, geometry);
            (!mesh.triangles.is_empty()).then(|| {
                meshes.push(mesh);
                Shape::Mesh(meshes.len() - 1)
            })
        }
        "ElevationGrid" => {
            let mesh = triangulate::elevation_grid(scene, geometry);
            (!mesh.triangles.is_empty()).then(|| {
                meshes.push(mesh);
                Shape::Mesh(meshes.len() - 1)
            })
        }
        _ => None,
    }
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
