//! Vertices of collision meshes (OBJ and STL), for convex-hull colliders.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;

/// Reads the vertices of an OBJ or STL file named in a URDF. `package://`
/// prefixes are dropped and relative names resolved in `mesh_dir`. Errors
/// carry the resolved path and what is wrong.
pub fn load_vertices(
    filename: &str,
    mesh_dir: Option<&Path>,
) -> Result<Vec<Vector3<f64>>, (PathBuf, String)> {
    let name = filename
        .strip_prefix("package://")
        .or_else(|| filename.strip_prefix("file://"))
        .unwrap_or(filename);
    let path = match mesh_dir {
        Some(dir) if Path::new(name).is_relative() => dir.join(name),
        Some(_) => PathBuf::from(name),
        None => {
            return Err((
                PathBuf::from(name),
                "meshes are not supported for a description given as text".to_string(),
            ));
        }
    };
    let bytes = std::fs::read(&path).map_err(|e| (path.clone(), format!("cannot read it: {e}")))?;
    let lower = name.to_ascii_lowercase();
    let points = if lower.ends_with(".obj") {
        parse_obj(&String::from_utf8_lossy(&bytes))
    } else if lower.ends_with(".stl") {
        parse_stl(&bytes)
    } else {
        Err("unsupported mesh format (use .obj or .stl)".to_string())
    }
    .map_err(|e| (path.clone(), e))?;
    if points.len() < 4 {
        return Err((
            path,
            format!(
                "has {} vertices; a convex hull needs at least 4",
                points.len()
            ),
        ));
    }
    Ok(points)
}

fn parse_obj(text: &str) -> Result<Vec<Vector3<f64>>, String> {
    let mut points = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        let coords: Vec<f64> = words
            .take(3)
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|_| format!("line {}: bad vertex {line:?}", n + 1))?;
        if coords.len() != 3 || coords.iter().any(|c| !c.is_finite()) {
            return Err(format!("line {}: bad vertex {line:?}", n + 1));
        }
        points.push(Vector3::new(coords[0], coords[1], coords[2]));
    }
    Ok(points)
}

fn parse_stl(bytes: &[u8]) -> Result<Vec<Vector3<f64>>, String> {
    let binary_len = |n: usize| 84 + 50 * n;
    if bytes.len() >= 84 {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if bytes.len() == binary_len(count) {
            let mut points = Vec::with_capacity(3 * count);
            for t in 0..count {
                let base = 84 + 50 * t + 12;
                for v in 0..3 {
                    let at = base + 12 * v;
                    let f = |k: usize| {
                        f32::from_le_bytes([
                            bytes[at + 4 * k],
                            bytes[at + 4 * k + 1],
                            bytes[at + 4 * k + 2],
                            bytes[at + 4 * k + 3],
                        ]) as f64
                    };
                    points.push(Vector3::new(f(0), f(1), f(2)));
                }
            }
            return Ok(points);
        }
    }
    let text =
        std::str::from_utf8(bytes).map_err(|_| "neither binary nor ASCII STL".to_string())?;
    let mut points = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("vertex") {
            continue;
        }
        let coords: Vec<f64> = words
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|_| format!("line {}: bad vertex", n + 1))?;
        if coords.len() != 3 {
            return Err(format!("line {}: bad vertex", n + 1));
        }
        points.push(Vector3::new(coords[0], coords[1], coords[2]));
    }
    Ok(points)
}
