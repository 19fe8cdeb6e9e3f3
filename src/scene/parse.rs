//! OWNED BY THE SCENE WORK ITEM — placeholder.
use super::Scene;
use std::path::Path;

pub(super) fn load_scene(path: &Path) -> crate::Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|source| crate::Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    scene_from_str(&text, path)
}

pub(super) fn scene_from_str(_text: &str, path: &Path) -> crate::Result<Scene> {
    Err(crate::Error::Scene {
        path: path.to_path_buf(),
        location: "file".into(),
        message: "parser not written yet".into(),
    })
}
