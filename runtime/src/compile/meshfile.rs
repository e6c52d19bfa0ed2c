//! Mesh files a Mesh or CadShape node names, decoded from the bytes the check read (the
//! scene's [`Asset`]s): Wavefront OBJ with its MTL colours through `tobj`, STL (binary or
//! ASCII) through `stl_io`. Collada is recognised and refused by name. A file that does not
//! decode is a reason, never a panic.

use std::io::{BufReader, Cursor};

use glam::DVec3;
use regatta_schema::Asset;

use super::graph::Mesh;

/// A decoded mesh file, with the colours its MTL gives each triangle (OBJ only).
pub struct MeshFile {
    pub mesh: Mesh,
    /// Per-triangle diffuse colours from the file's materials, when it has any.
    pub colors: Option<Vec<[f64; 3]>>,
}

/// Decodes an asset by its url's extension (or, for an STL, its content); `ccw FALSE` turns
/// every triangle.
pub fn decode(asset: &Asset, ccw: bool) -> Result<MeshFile, String> {
    let url = &asset.url;
    let extension = url
        .rsplit_once('.')
        .map(|(_, e)| e.to_ascii_lowercase())
        .unwrap_or_default();
    let mut file = match extension.as_str() {
        "obj" => obj(asset)?,
        "stl" => stl(url, &asset.bytes)?,
        "dae" => {
            return Err(format!(
                "'{url}' is a Collada file, which regatta does not read"
            ))
        }
        _ => return Err(format!("'{url}' is not an OBJ or STL file")),
    };
    // A point at infinity or NaN would poison bounds and exports: its triangles go.
    let positions = &file.mesh.positions;
    let finite = |t: &[u32; 3]| t.iter().all(|&i| positions[i as usize].is_finite());
    if !file.mesh.triangles.iter().all(finite) {
        let keep: Vec<bool> = file.mesh.triangles.iter().map(finite).collect();
        let mut k = keep.iter();
        file.mesh.triangles.retain(|_| *k.next().unwrap_or(&false));
        if let Some(colors) = &mut file.colors {
            let mut k = keep.iter();
            colors.retain(|_| *k.next().unwrap_or(&false));
        }
    }
    if file.mesh.triangles.is_empty() {
        return Err(format!("'{url}' holds no triangles"));
    }
    if !ccw {
        for t in &mut file.mesh.triangles {
            t.swap(1, 2);
        }
    }
    Ok(file)
}

fn obj(asset: &Asset) -> Result<MeshFile, String> {
    let url = &asset.url;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let mut reader = BufReader::new(Cursor::new(&asset.bytes[..]));
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |path| {
        let name = path.to_string_lossy();
        match asset.companions.iter().find(|c| c.name == name) {
            Some(companion) => match &companion.bytes {
                Ok(bytes) => tobj::load_mtl_buf(&mut BufReader::new(Cursor::new(&bytes[..]))),
                Err(_) => Err(tobj::LoadError::OpenFileFailed),
            },
            None => Err(tobj::LoadError::OpenFileFailed),
        }
    })
    .map_err(|e| format!("'{url}' is not a valid OBJ file ({e})"))?;
    // Missing MTL files leave the shape's own appearance.
    let materials = materials.unwrap_or_default();
    let mut mesh = Mesh {
        solid: true,
        // Webots smooths mesh files' normals where the file gives none; a crease angle of
        // about 60° keeps hard edges hard.
        crease_angle: 1.0,
        ..Mesh::default()
    };
    let mut colors = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let first = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)),
        );
        let color = m
            .material_id
            .and_then(|i| materials.get(i))
            .and_then(|mat| mat.diffuse)
            .map(|d| d.map(|c| c as f64));
        for t in m.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= count) {
                continue;
            }
            mesh.triangles
                .push([first + t[0], first + t[1], first + t[2]]);
            colors.push(color);
        }
    }
    let colors = colors
        .iter()
        .any(Option::is_some)
        .then(|| colors.iter().map(|c| c.unwrap_or([0.8; 3])).collect());
    Ok(MeshFile { mesh, colors })
}

fn stl(url: &str, bytes: &[u8]) -> Result<MeshFile, String> {
    let indexed = stl_io::read_stl(&mut Cursor::new(bytes))
        .map_err(|e| format!("'{url}' is not a valid STL file ({e})"))?;
    let positions: Vec<DVec3> = indexed
        .vertices
        .iter()
        .map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
        .collect();
    let triangles = indexed
        .faces
        .iter()
        .filter(|f| f.vertices.iter().all(|&i| i < positions.len()))
        .map(|f| f.vertices.map(|i| i as u32))
        .collect();
    Ok(MeshFile {
        mesh: Mesh {
            positions,
            triangles,
            solid: true,
            crease_angle: 1.0,
            ..Mesh::default()
        },
        colors: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use regatta_schema::{Companion, NodeId};

    fn asset(url: &str, bytes: &[u8], companions: Vec<Companion>) -> Asset {
        Asset {
            node: NodeId(0),
            url: url.to_owned(),
            bytes: bytes.into(),
            companions,
        }
    }

    #[test]
    fn an_obj_with_its_mtl_colours_its_triangles() {
        let obj = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl red\nf 1 2 3 4\n";
        let mtl = b"newmtl red\nKd 1 0 0\n";
        let companions = vec![Companion {
            name: "m.mtl".to_owned(),
            bytes: Ok(mtl.as_slice().into()),
        }];
        let file = decode(&asset("a.obj", obj, companions), true).unwrap();
        assert_eq!(file.mesh.triangles.len(), 2);
        assert_eq!(file.colors, Some(vec![[1.0, 0.0, 0.0]; 2]));
    }

    #[test]
    fn an_ascii_stl_reads_and_garbage_is_a_reason() {
        let stl = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let file = decode(&asset("a.stl", stl, Vec::new()), true).unwrap();
        assert_eq!(file.mesh.triangles.len(), 1);
        for (url, bytes) in [
            ("b.stl", b"\x00\x01garbage".as_slice()),
            ("c.obj", b"f 1 2 3\n".as_slice()),
            ("d.dae", b"<COLLADA/>".as_slice()),
            ("e.ply", b"ply".as_slice()),
        ] {
            let reason = decode(&asset(url, bytes, Vec::new()), true).err().unwrap();
            assert!(reason.contains(url), "{reason}");
        }
    }

    #[test]
    fn hostile_objs_are_reasons_or_meshes_never_a_panic() {
        for text in [
            "v 0 0 0\nf -100 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 0 0\n",
            "v 1e400 nan inf\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0\nf 1/99/99 1/-5 1//7\n",
            "f 4294967295 4294967294 1\n",
            "mtllib\nusemtl\nnewmtl\nv\nvt\nvn\nf\nl 1 2\np 1\ng\no\ns off\n",
            "\u{0}\u{1}\u{2}binary",
        ] {
            if let Ok(file) = decode(&asset("h.obj", text.as_bytes(), Vec::new()), true) {
                assert!(
                    file.mesh.used_positions().all(|p| p.is_finite()),
                    "{text:?}"
                );
            }
        }
    }

    #[test]
    fn a_binary_stl_that_claims_more_triangles_than_it_holds_is_refused() {
        let mut bytes = vec![0u8; 80];
        bytes.extend_from_slice(&u32::MAX.to_le_bytes());
        bytes.extend_from_slice(&[0u8; 50]);
        assert!(decode(&asset("big.stl", &bytes, Vec::new()), true).is_err());
    }
}
