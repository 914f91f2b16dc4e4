//! The scene's `[fit]` table read into what the command line would otherwise give: the
//! free parameters ([`free_of_scene`], each entry read as `--free` reads it) and the
//! data file ([`data_of_scene`], relative to the scene file). An entry that cannot be
//! used is an error at its line, with its value.

use std::path::{Path, PathBuf};

use toml::Spanned;

use super::FreeParameter;
use crate::scene::{SceneError, SceneFile};

/// The free parameters of the scene's `[fit]` table, in their order; empty when the
/// scene has no `[fit] free`. An entry that does not read as `NAME`, `NAME>=LO`,
/// `NAME<=HI` or `NAME in [LO, HI]`, names no parameter of the scene, or repeats an
/// earlier one is an error at its line.
pub fn free_of_scene(file: &SceneFile) -> Result<Vec<FreeParameter>, SceneError> {
    let Some(table) = &file.fit else { return Ok(Vec::new()) };
    let mut free: Vec<FreeParameter> = Vec::with_capacity(table.free.len());
    for entry in &table.free {
        let p = FreeParameter::parse(entry.get_ref()).map_err(|e| invalid(file, entry, format!("[fit] free: {e}")))?;
        if !file.parameters.contains_key(&p.name) {
            let known = file.parameters.keys().map(String::as_str).collect::<Vec<_>>().join(", ");
            let message = format!("[fit] free: `{}` is not a parameter of the scene (its parameters: {known})", p.name);
            return Err(invalid(file, entry, message));
        }
        if free.iter().any(|q| q.name == p.name) {
            return Err(invalid(file, entry, format!("[fit] free: `{}` is named twice", p.name)));
        }
        free.push(p);
    }
    Ok(free)
}

/// The data file of the scene's `[fit]` table: relative to the scene file's directory
/// (to the working directory for a scene built in code), an absolute path as written;
/// `None` when the scene names none. An empty path is an error at its line.
pub fn data_of_scene(file: &SceneFile) -> Result<Option<PathBuf>, SceneError> {
    let Some(data) = file.fit.as_ref().and_then(|t| t.data.as_ref()) else { return Ok(None) };
    if data.get_ref().trim().is_empty() {
        return Err(invalid(file, data, "[fit] data: the data file's path is empty".to_string()));
    }
    let path = Path::new(data.get_ref());
    let dir = match file.origin.fields {
        None => Path::new(&file.origin.path).parent().unwrap_or(Path::new("")),
        Some(_) => Path::new(""),
    };
    Ok(Some(if path.is_absolute() { path.to_path_buf() } else { dir.join(path) }))
}

fn invalid<T>(file: &SceneFile, v: &Spanned<T>, message: String) -> SceneError {
    SceneError::Invalid { location: file.origin.locate_in(v, None), message }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"[scene]
name = "oscillator"
lagrangian = "1/2*x_dot^2 - 1/2*k*x^2"

[parameters]
k = 2
x0 = 1

[[coordinates]]
name = "x"
initial = "x0"
velocity = 0

[time]
start = 0
end = 1
nodes = 32
"#;

    fn scene_with(fit: &str) -> SceneFile {
        SceneFile::parse(&format!("{SCENE}\n[fit]\n{fit}"), "dir/scene.toml").unwrap()
    }

    #[test]
    fn the_table_gives_the_free_parameters_and_the_data_beside_the_scene() {
        let file = scene_with("free = [\"k>=0\", \"x0 in [0, 2]\"]\ndata = \"data/x.csv\"\n");
        let free = free_of_scene(&file).unwrap();
        assert_eq!(free, [FreeParameter::parse("k>=0").unwrap(), FreeParameter::parse("x0 in [0, 2]").unwrap()]);
        assert_eq!(data_of_scene(&file).unwrap(), Some(PathBuf::from("dir/data/x.csv")));
        let plain = SceneFile::parse(SCENE, "scene.toml").unwrap();
        assert!(free_of_scene(&plain).unwrap().is_empty() && data_of_scene(&plain).unwrap().is_none());
    }

    #[test]
    fn a_bad_entry_is_an_error_at_its_line_with_its_value() {
        // `[fit]` is line 19 of the scene's text, its first key line 20.
        for (fit, expected) in [
            ("free = [\"k\", \"x0 in [2, 0]\"]", "dir/scene.toml:20:14: [fit] free: free parameter `x0 in [2, 0]`: the lower bound 2"),
            ("free = [\"k\",\n  \"q>=0\"]", "dir/scene.toml:21:3: [fit] free: `q` is not a parameter of the scene (its parameters: k, x0)"),
            ("free = [\"k\", \"k<=3\"]", "dir/scene.toml:20:14: [fit] free: `k` is named twice"),
            ("data = \" \"", "dir/scene.toml:20:8: [fit] data: the data file's path is empty"),
        ] {
            let file = scene_with(fit);
            let e = free_of_scene(&file).err().or_else(|| data_of_scene(&file).err()).expect(fit);
            assert!(e.to_string().starts_with(expected), "{fit}: {e}");
        }
        let e = SceneFile::parse(&format!("{SCENE}\n[fit]\nfree = [\"k\"]\nsigma = 1\n"), "s.toml").unwrap_err();
        assert!(e.to_string().contains("s.toml:21:1") && e.to_string().contains("sigma"), "{e}");
    }
}
