//! `pipeline::cache`: an entry is read back only whole and under its own key
//! (a corrupt, cut-short, foreign or NaN entry is a miss), a miss is rewritten by
//! the command that uses the cache, and the key follows the scene file's content.

use gradtrace::math::Vec3;
use gradtrace::output::{ExrHeader, OutputImage};
use gradtrace::pipeline::cache::{byte_entry_payload, Cache, Epoch};
use gradtrace::pipeline::preview::shadow_field::{self, ShadowFieldOptions};
use gradtrace::preview::shadow_field::Settings;
use std::path::{Path, PathBuf};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-cache-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_byte_entry_is_read_only_whole_and_under_its_key() {
    let dir = temp_dir("bytes");
    let cache = Cache::under(&dir);
    let entry = cache.entry("t", "bin", Epoch::Source, "scene-a", "settings");
    let other = cache.entry("t", "bin", Epoch::Source, "scene-b", "settings");
    assert_ne!(entry.key(), other.key());
    assert_ne!(entry.path(), other.path());
    assert!(entry.path().starts_with(dir.join("cache")));
    assert!(entry.read_bytes().is_none(), "nothing written yet");
    let payload: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
    entry.write_bytes(&payload, 1.5).unwrap();
    let hit = entry.read_bytes().expect("a whole entry is a hit");
    assert_eq!(
        (hit.value.as_slice(), hit.seconds),
        (payload.as_slice(), 1.5)
    );
    let good = std::fs::read(entry.path()).unwrap();
    let is_miss = |bytes: &[u8], what: &str| {
        std::fs::write(entry.path(), bytes).unwrap();
        assert!(entry.read_bytes().is_none(), "{what} must be a miss");
    };
    // One flipped bit in the payload, and in the header's key.
    let mut flipped = good.clone();
    *flipped.last_mut().unwrap() ^= 1;
    is_miss(&flipped, "a flipped payload bit");
    let mut flipped = good.clone();
    flipped[20] ^= 1;
    is_miss(&flipped, "a flipped key bit");
    is_miss(&good[..good.len() - 1], "an entry cut short");
    is_miss(&good[..10], "an entry cut in its header");
    is_miss(&[], "an empty file");
    // Another key's entry under this one's name (a prefix collision, a copy).
    other.write_bytes(&payload, 1.5).unwrap();
    is_miss(&std::fs::read(other.path()).unwrap(), "another key's entry");
    // The miss is rewritten whole.
    entry.write_bytes(&payload, 2.5).unwrap();
    assert_eq!(entry.read_bytes().map(|h| h.seconds), Some(2.5));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The tools handed a cache file by path (`examples/glossy_frame.rs`) read its
/// payload past the header; before, they handed the header to the decoder.
#[test]
fn a_byte_entry_file_yields_its_payload() {
    let dir = temp_dir("payload");
    let entry = Cache::under(&dir).entry("t", "bin", Epoch::Source, "scene", "settings");
    // A payload that itself holds newlines and the magic line.
    let payload = b"gradtrace cache 1\nline\n\n\x00\xff".to_vec();
    entry.write_bytes(&payload, 3.0).unwrap();
    let file = std::fs::read(entry.path()).unwrap();
    assert_eq!(byte_entry_payload(&file), Some(payload.as_slice()));
    assert_eq!(byte_entry_payload(&payload[..5]), None, "no header");
    assert_eq!(
        byte_entry_payload(b"GTGLOSS5\n1\n2\n3\n4\nx"),
        None,
        "no magic"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_exr_entry_with_a_nan_or_of_another_key_is_a_miss() {
    let dir = temp_dir("exr");
    let cache = Cache::beside(&dir);
    let entry = cache.entry("reference", "exr", Epoch::Pixels, "scene", "spp 4");
    assert_eq!(entry.path().parent(), Some(dir.as_path()));
    let (w, h) = (3, 2);
    let beauty: Vec<Vec3> = (0..w * h).map(|i| Vec3::splat(0.25 * i as f32)).collect();
    let mut img = OutputImage::new(w, h);
    img.push_vec3("", ["R", "G", "B"], &beauty);
    entry
        .write_exr(&img, &ExrHeader::default(), &beauty, 0.75)
        .unwrap();
    let hit = entry.read_exr(|i| (i.width, i.height) == (w, h)).unwrap();
    assert_eq!(hit.value.vec3("", ["R", "G", "B"]).unwrap(), beauty);
    assert_eq!(hit.seconds, 0.75);
    // The caller's check (here: a size) decides too.
    assert!(entry.read_exr(|i| i.width == w + 1).is_none());
    // A NaN in the file (written by another tool, its header intact) is a miss.
    set_first_sample(entry.path(), f32::NAN);
    assert!(entry.read_exr(|_| true).is_none(), "a NaN must be a miss");
    set_first_sample(entry.path(), 0.0);
    assert!(entry.read_exr(|_| true).is_some(), "the edit keeps the key");
    // A plain EXR, without this key, is a miss.
    gradtrace::output::write_exr(entry.path(), &img).unwrap();
    assert!(entry.read_exr(|_| true).is_none());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Rewrites `path`'s first sample, keeping its header (with the cache key).
fn set_first_sample(path: &Path, value: f32) {
    use exr::prelude::*;
    let mut image = read_all_flat_layers_from_file(path).unwrap();
    match &mut image.layer_data[0].channel_data.list[0].sample_data {
        FlatSamples::F32(v) => v[0] = value,
        other => panic!("expected f32 samples, found {other:?}"),
    }
    image.write().to_file(path).unwrap();
}

#[test]
fn a_changed_scene_file_changes_the_key() {
    let dir = temp_dir("scene");
    let path = dir.join("scene.toml");
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/spheres_table.toml"
    ))
    .unwrap();
    let key = |text: &str| {
        std::fs::write(&path, text).unwrap();
        let scene = gradtrace::scene::load(&path).unwrap();
        let hash = scene.content_hash().unwrap();
        // Memoised: the same answer again, without reading the files.
        assert_eq!(scene.content_hash().unwrap(), hash);
        Cache::under(&dir)
            .entry("t", "bin", Epoch::Source, &hash, "s")
            .key()
            .to_string()
    };
    let k0 = key(&text);
    assert_eq!(key(&text), k0, "the same content, the same key");
    assert_ne!(key(&format!("{text}\n# edited\n")), k0);
    assert_ne!(key(&text.replace("exponent = 60", "exponent = 61")), k0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// End to end through a user: the shadow-field preview recomputes a damaged
/// cache entry and rewrites it, so that the next run reads it again.
#[test]
fn a_corrupt_shadow_field_cache_is_recomputed_and_rewritten() {
    let dir = temp_dir("sf");
    let mut opts = ShadowFieldOptions::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/shadowfield_deform.toml"
    ));
    opts.out_dir = dir.clone();
    opts.quiet = true;
    opts.resolution = Some((24, 18));
    opts.reference_spp = Some(4);
    opts.reference_spp_max = Some(4);
    opts.settings = Settings {
        rays: 8,
        self_rays: 4,
        ..Settings::default()
    };
    let first = shadow_field::run(&opts).unwrap();
    assert!(!first.precompute_cached);
    let entries: Vec<PathBuf> = std::fs::read_dir(dir.join("cache"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "bin"))
        .collect();
    assert_eq!(entries.len(), 1, "{entries:?}");
    let second = shadow_field::run(&opts).unwrap();
    assert!(second.precompute_cached);
    assert_eq!(second.precompute_s, first.precompute_s);
    let mut bytes = std::fs::read(&entries[0]).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    std::fs::write(&entries[0], &bytes).unwrap();
    let third = shadow_field::run(&opts).unwrap();
    assert!(!third.precompute_cached, "a corrupt entry is a miss");
    assert_ne!(
        std::fs::read(&entries[0]).unwrap(),
        bytes,
        "and is rewritten"
    );
    assert!(shadow_field::run(&opts).unwrap().precompute_cached);
    let _ = std::fs::remove_dir_all(&dir);
}
