//! Pins the pixels: every bundled scene, in every mode (path, direct, `--gradients`,
//! `--strategy` with both interpolations), rendered small by the `gradtrace` binary,
//! with a checksum per EXR channel compared against the table below. A refactor
//! that changes any bit of any layer fails here.
//!
//! When a change is *meant* to change pixels, print the new table with
//! `GRADTRACE_PIN_PRINT=1 cargo test --release --test pixels_pinned -- --nocapture`,
//! paste it below and say in the commit which layers moved and why.

use gradtrace::output::read_exr;
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_gradtrace");

const SCENES: &[&str] = &[
    "scenes/cornell.toml",
    "scenes/spheres_table.toml",
    "scenes/spheres_table_far.toml",
    "scenes/three_spheres_env.toml",
    "scenes/objects_bumpy.toml",
    "scenes/bunny_env.toml",
    "scenes/validation/cornell.toml",
    "scenes/validation/env_constant.toml",
    "scenes/validation/env_image.toml",
    "scenes/validation/spheres.toml",
];

/// (mode name, extra flags). Small images and few samples keep the whole table
/// under a minute; every code path of the renderer still runs.
const MODES: &[(&str, &[&str])] = &[
    ("path", &["--integrator", "path", "--spp", "4"]),
    ("direct", &["--integrator", "direct", "--spp", "4"]),
    (
        "gradients",
        &["--gradients", "--vis-samples", "4", "--spp", "4"],
    ),
    (
        "strategy-gradient",
        &["--strategy", "gradient", "--budget", "0.3", "--spp", "4"],
    ),
    (
        "strategy-variance-linear",
        &[
            "--strategy",
            "variance",
            "--budget",
            "0.2",
            "--interpolation",
            "linear",
            "--spp",
            "4",
        ],
    ),
];

/// FNV-1a over the f32 bit patterns: any change of any bit changes it.
fn fnv1a(data: &[f32]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in data {
        for b in v.to_bits().to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Renders one scene in one mode and returns "scene mode channel=hash" lines.
fn checksums(scene: &str, mode: &str, flags: &[&str], dir: &Path) -> Vec<String> {
    let exr = dir.join(format!("{}-{mode}.exr", scene.replace(['/', '.'], "_")));
    let out = Command::new(BIN)
        .arg("render")
        .arg(root().join(scene))
        .args(["--width", "40", "--height", "30", "--seed", "7", "--quiet"])
        .args(flags)
        .arg("--out")
        .arg(&exr)
        .output()
        .expect("the binary runs");
    assert!(
        out.status.success(),
        "{scene} {mode}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = read_exr(&exr).unwrap();
    let mut lines: Vec<String> = img
        .channels
        .iter()
        .map(|c| format!("{scene} {mode} {}={:016x}", c.name, fnv1a(&c.data)))
        .collect();
    lines.sort();
    lines
}

#[test]
fn every_scene_and_mode_renders_the_pinned_pixels() {
    let dir = std::env::temp_dir().join(format!("gradtrace-pins-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut got = Vec::new();
    for scene in SCENES {
        for (mode, flags) in MODES {
            got.extend(checksums(scene, mode, flags, &dir));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    if std::env::var_os("GRADTRACE_PIN_PRINT").is_some() {
        println!("const PINNED: &str = \"\\\n{}\";", got.join("\n"));
    }
    let want: Vec<&str> = PINNED.lines().filter(|l| !l.trim().is_empty()).collect();
    let mismatched: Vec<String> = got
        .iter()
        .filter(|g| !want.contains(&g.as_str()))
        .cloned()
        .collect();
    assert!(
        mismatched.is_empty() && got.len() == want.len(),
        "{} of {} channel checksums differ from the pinned table ({} pinned); first: {:?}",
        mismatched.len(),
        got.len(),
        want.len(),
        mismatched.iter().take(8).collect::<Vec<_>>()
    );
}

const PINNED: &str = "\
scenes/cornell.toml path B=ea465850abd8eb4d
scenes/cornell.toml path G=59bd8def348513c8
scenes/cornell.toml path R=0a31583d153692d7
scenes/cornell.toml path albedo.B=1cf114732f212c55
scenes/cornell.toml path albedo.G=c2e25bc731600b34
scenes/cornell.toml path albedo.R=bd8f4061c03a3b1e
scenes/cornell.toml path depth.Z=5fdf8f96653d961e
scenes/cornell.toml path normal.X=1803733917ef30e6
scenes/cornell.toml path normal.Y=fe7cc7029d2c44f8
scenes/cornell.toml path normal.Z=f4004e0ae60494c2
scenes/cornell.toml path object.id=cfa4cc5220d1e4e5
scenes/cornell.toml path variance.B=c3fe4746cbd48612
scenes/cornell.toml path variance.G=a8acddcf881aaebe
scenes/cornell.toml path variance.R=6bd3515f46602ce1
scenes/cornell.toml direct B=f437ba6bb8b1ee42
scenes/cornell.toml direct G=c135c01c7d9ef14e
scenes/cornell.toml direct R=3bb4dbde5ddeb4b1
scenes/cornell.toml direct albedo.B=1cf114732f212c55
scenes/cornell.toml direct albedo.G=c2e25bc731600b34
scenes/cornell.toml direct albedo.R=bd8f4061c03a3b1e
scenes/cornell.toml direct depth.Z=5fdf8f96653d961e
scenes/cornell.toml direct normal.X=1803733917ef30e6
scenes/cornell.toml direct normal.Y=fe7cc7029d2c44f8
scenes/cornell.toml direct normal.Z=f4004e0ae60494c2
scenes/cornell.toml direct object.id=cfa4cc5220d1e4e5
scenes/cornell.toml direct variance.B=90a12c1e9c83fe1b
scenes/cornell.toml direct variance.G=7b1e4d95fe0fc2a7
scenes/cornell.toml direct variance.R=fb21fc9ff249e3c7
scenes/cornell.toml gradients B=fedb66d286bbf721
scenes/cornell.toml gradients G=64ed92e6d63e98a5
scenes/cornell.toml gradients R=6745b337285e9af7
scenes/cornell.toml gradients albedo.B=1cf114732f212c55
scenes/cornell.toml gradients albedo.G=c2e25bc731600b34
scenes/cornell.toml gradients albedo.R=bd8f4061c03a3b1e
scenes/cornell.toml gradients depth.Z=5fdf8f96653d961e
scenes/cornell.toml gradients grad.cdv.Y=d0549f149dd63a25
scenes/cornell.toml gradients grad.cv.Y=d0549f149dd63a25
scenes/cornell.toml gradients grad.dv.Y=d0549f149dd63a25
scenes/cornell.toml gradients grad.indirect.Y=d0549f149dd63a25
scenes/cornell.toml gradients grad.ratio.Y=d0549f149dd63a25
scenes/cornell.toml gradients grad.sv.Y=18d5ee780f7dd827
scenes/cornell.toml gradients grad.u.B=d4b4f4cf092e281b
scenes/cornell.toml gradients grad.u.G=acc8949ee6760e50
scenes/cornell.toml gradients grad.u.R=cc48eac840af2061
scenes/cornell.toml gradients grad.v.B=abcd81eafd9fa93a
scenes/cornell.toml gradients grad.v.G=0e7a44fef20565e6
scenes/cornell.toml gradients grad.v.R=d43da96d37abb4fb
scenes/cornell.toml gradients grad.vis.Y=8cecede4d90f592f
scenes/cornell.toml gradients normal.X=1803733917ef30e6
scenes/cornell.toml gradients normal.Y=fe7cc7029d2c44f8
scenes/cornell.toml gradients normal.Z=f4004e0ae60494c2
scenes/cornell.toml gradients object.id=cfa4cc5220d1e4e5
scenes/cornell.toml gradients variance.B=69133737215e5754
scenes/cornell.toml gradients variance.G=14964478204fdfff
scenes/cornell.toml gradients variance.R=125c5fb959000a0e
scenes/cornell.toml strategy-gradient B=5aab134d653c59de
scenes/cornell.toml strategy-gradient G=23c29710ef1047ab
scenes/cornell.toml strategy-gradient R=130fd1f1b0b3ff0b
scenes/cornell.toml strategy-gradient albedo.B=b0d7f7c8e3a1d98c
scenes/cornell.toml strategy-gradient albedo.G=a6e5f6bec7d3e956
scenes/cornell.toml strategy-gradient albedo.R=bc2325996af6d5c1
scenes/cornell.toml strategy-gradient depth.Z=3b2b09fe2e03b651
scenes/cornell.toml strategy-gradient normal.X=0f19db890af620ec
scenes/cornell.toml strategy-gradient normal.Y=e23462326f60e135
scenes/cornell.toml strategy-gradient normal.Z=8ed30f96d14d5cd2
scenes/cornell.toml strategy-gradient object.id=cfa4cc5220d1e4e5
scenes/cornell.toml strategy-gradient samples.Y=cec89e5e661a6ab8
scenes/cornell.toml strategy-gradient samples.density=4fbc41aecbd31225
scenes/cornell.toml strategy-variance-linear B=f98b5761bd3f2d1c
scenes/cornell.toml strategy-variance-linear G=fe2e7a0707e46fc2
scenes/cornell.toml strategy-variance-linear R=7cde024aa57871b1
scenes/cornell.toml strategy-variance-linear albedo.B=b0d7f7c8e3a1d98c
scenes/cornell.toml strategy-variance-linear albedo.G=a6e5f6bec7d3e956
scenes/cornell.toml strategy-variance-linear albedo.R=bc2325996af6d5c1
scenes/cornell.toml strategy-variance-linear depth.Z=3b2b09fe2e03b651
scenes/cornell.toml strategy-variance-linear normal.X=0f19db890af620ec
scenes/cornell.toml strategy-variance-linear normal.Y=e23462326f60e135
scenes/cornell.toml strategy-variance-linear normal.Z=8ed30f96d14d5cd2
scenes/cornell.toml strategy-variance-linear object.id=cfa4cc5220d1e4e5
scenes/cornell.toml strategy-variance-linear samples.Y=646f054409cfb6d8
scenes/cornell.toml strategy-variance-linear samples.density=010df02a9ac1c505
scenes/spheres_table.toml path B=7da12f3a7150fd4c
scenes/spheres_table.toml path G=bc3f68a917878b11
scenes/spheres_table.toml path R=e9825ad26efca24c
scenes/spheres_table.toml path albedo.B=59e42a92276f1ca6
scenes/spheres_table.toml path albedo.G=a0ffce79ae2e26da
scenes/spheres_table.toml path albedo.R=98ae98710f2deccf
scenes/spheres_table.toml path depth.Z=c654d3fe05287b31
scenes/spheres_table.toml path normal.X=36b2c8c01db5115b
scenes/spheres_table.toml path normal.Y=3bd6e75721f15fd7
scenes/spheres_table.toml path normal.Z=2fbf8d3c2e020bc0
scenes/spheres_table.toml path object.id=b25d66d3a2238c85
scenes/spheres_table.toml path variance.B=14669a0c62997bbb
scenes/spheres_table.toml path variance.G=aa43ee3cca26d2cf
scenes/spheres_table.toml path variance.R=fc1183cef924608f
scenes/spheres_table.toml direct B=2a0d6b14bf0cd5f0
scenes/spheres_table.toml direct G=0f541954397f9ebd
scenes/spheres_table.toml direct R=06aa2ae4be42c9ed
scenes/spheres_table.toml direct albedo.B=59e42a92276f1ca6
scenes/spheres_table.toml direct albedo.G=a0ffce79ae2e26da
scenes/spheres_table.toml direct albedo.R=98ae98710f2deccf
scenes/spheres_table.toml direct depth.Z=c654d3fe05287b31
scenes/spheres_table.toml direct normal.X=36b2c8c01db5115b
scenes/spheres_table.toml direct normal.Y=3bd6e75721f15fd7
scenes/spheres_table.toml direct normal.Z=2fbf8d3c2e020bc0
scenes/spheres_table.toml direct object.id=b25d66d3a2238c85
scenes/spheres_table.toml direct variance.B=cbd3a6160956a263
scenes/spheres_table.toml direct variance.G=d956d4f6e8981437
scenes/spheres_table.toml direct variance.R=d2ed9e98a5eeb08d
scenes/spheres_table.toml gradients B=d0c46811150a0f95
scenes/spheres_table.toml gradients G=918a30180cc28e34
scenes/spheres_table.toml gradients R=45af37b19b625001
scenes/spheres_table.toml gradients albedo.B=59e42a92276f1ca6
scenes/spheres_table.toml gradients albedo.G=a0ffce79ae2e26da
scenes/spheres_table.toml gradients albedo.R=98ae98710f2deccf
scenes/spheres_table.toml gradients depth.Z=c654d3fe05287b31
scenes/spheres_table.toml gradients grad.cdv.Y=2a1c1944e77ed730
scenes/spheres_table.toml gradients grad.cv.Y=8f96419e5fae73b4
scenes/spheres_table.toml gradients grad.dv.Y=34ef69033dcef542
scenes/spheres_table.toml gradients grad.indirect.Y=529cf34f355a6dae
scenes/spheres_table.toml gradients grad.ratio.Y=0ba65f530d126318
scenes/spheres_table.toml gradients grad.sv.Y=731b1326834f7f4d
scenes/spheres_table.toml gradients grad.u.B=34715f51b59930c5
scenes/spheres_table.toml gradients grad.u.G=6ff29c1ccdf3c08e
scenes/spheres_table.toml gradients grad.u.R=84741795cb1ebdc1
scenes/spheres_table.toml gradients grad.v.B=086c9feb8523bcf9
scenes/spheres_table.toml gradients grad.v.G=c8e72edf3b4c9a29
scenes/spheres_table.toml gradients grad.v.R=ec8df9b9132fdfd8
scenes/spheres_table.toml gradients grad.vis.Y=8c7a85dc52e27f04
scenes/spheres_table.toml gradients normal.X=36b2c8c01db5115b
scenes/spheres_table.toml gradients normal.Y=3bd6e75721f15fd7
scenes/spheres_table.toml gradients normal.Z=2fbf8d3c2e020bc0
scenes/spheres_table.toml gradients object.id=b25d66d3a2238c85
scenes/spheres_table.toml gradients variance.B=94eb01d1af41fa81
scenes/spheres_table.toml gradients variance.G=96d7d798f8349439
scenes/spheres_table.toml gradients variance.R=34d02d6cac6aa722
scenes/spheres_table.toml strategy-gradient B=1efbba08b9c2c422
scenes/spheres_table.toml strategy-gradient G=33e8473e71e5c3a2
scenes/spheres_table.toml strategy-gradient R=4d10ca7cdacaf5f6
scenes/spheres_table.toml strategy-gradient albedo.B=d6359a6ac508356d
scenes/spheres_table.toml strategy-gradient albedo.G=510fc67fd5869831
scenes/spheres_table.toml strategy-gradient albedo.R=43818e9a6c8ecb6c
scenes/spheres_table.toml strategy-gradient depth.Z=87a8c99f8f89b06e
scenes/spheres_table.toml strategy-gradient normal.X=b42cd495d305cf4a
scenes/spheres_table.toml strategy-gradient normal.Y=17740a74e189ec07
scenes/spheres_table.toml strategy-gradient normal.Z=e169ea7253b99c9c
scenes/spheres_table.toml strategy-gradient object.id=b25d66d3a2238c85
scenes/spheres_table.toml strategy-gradient samples.Y=a82a3ee7f5f547c5
scenes/spheres_table.toml strategy-gradient samples.density=836f412701b42b75
scenes/spheres_table.toml strategy-variance-linear B=f7260c82ea344086
scenes/spheres_table.toml strategy-variance-linear G=c43fff9a2e46269f
scenes/spheres_table.toml strategy-variance-linear R=fd7f93661d30d4f7
scenes/spheres_table.toml strategy-variance-linear albedo.B=d6359a6ac508356d
scenes/spheres_table.toml strategy-variance-linear albedo.G=510fc67fd5869831
scenes/spheres_table.toml strategy-variance-linear albedo.R=43818e9a6c8ecb6c
scenes/spheres_table.toml strategy-variance-linear depth.Z=87a8c99f8f89b06e
scenes/spheres_table.toml strategy-variance-linear normal.X=b42cd495d305cf4a
scenes/spheres_table.toml strategy-variance-linear normal.Y=17740a74e189ec07
scenes/spheres_table.toml strategy-variance-linear normal.Z=e169ea7253b99c9c
scenes/spheres_table.toml strategy-variance-linear object.id=b25d66d3a2238c85
scenes/spheres_table.toml strategy-variance-linear samples.Y=72e8f30619bfaef8
scenes/spheres_table.toml strategy-variance-linear samples.density=148dd1a96bff26c5
scenes/spheres_table_far.toml path B=6e9b29440ad5e121
scenes/spheres_table_far.toml path G=0473a552bdb97463
scenes/spheres_table_far.toml path R=3c6a5b8b2de976d7
scenes/spheres_table_far.toml path albedo.B=59e42a92276f1ca6
scenes/spheres_table_far.toml path albedo.G=a0ffce79ae2e26da
scenes/spheres_table_far.toml path albedo.R=98ae98710f2deccf
scenes/spheres_table_far.toml path depth.Z=c654d3fe05287b31
scenes/spheres_table_far.toml path normal.X=36b2c8c01db5115b
scenes/spheres_table_far.toml path normal.Y=3bd6e75721f15fd7
scenes/spheres_table_far.toml path normal.Z=2fbf8d3c2e020bc0
scenes/spheres_table_far.toml path object.id=b25d66d3a2238c85
scenes/spheres_table_far.toml path variance.B=52c607621d48433d
scenes/spheres_table_far.toml path variance.G=8335f217bdb6298e
scenes/spheres_table_far.toml path variance.R=5fba5fd9ed0f74f1
scenes/spheres_table_far.toml direct B=9671e1df754517f3
scenes/spheres_table_far.toml direct G=a5e262e614ac38ff
scenes/spheres_table_far.toml direct R=cbb42cfb23bf0775
scenes/spheres_table_far.toml direct albedo.B=59e42a92276f1ca6
scenes/spheres_table_far.toml direct albedo.G=a0ffce79ae2e26da
scenes/spheres_table_far.toml direct albedo.R=98ae98710f2deccf
scenes/spheres_table_far.toml direct depth.Z=c654d3fe05287b31
scenes/spheres_table_far.toml direct normal.X=36b2c8c01db5115b
scenes/spheres_table_far.toml direct normal.Y=3bd6e75721f15fd7
scenes/spheres_table_far.toml direct normal.Z=2fbf8d3c2e020bc0
scenes/spheres_table_far.toml direct object.id=b25d66d3a2238c85
scenes/spheres_table_far.toml direct variance.B=2428cd0a8da01cbc
scenes/spheres_table_far.toml direct variance.G=59beeef6571faeac
scenes/spheres_table_far.toml direct variance.R=8e1badd23656f8cb
scenes/spheres_table_far.toml gradients B=c5199623c059454b
scenes/spheres_table_far.toml gradients G=033bc4cf6d23734f
scenes/spheres_table_far.toml gradients R=b76787428934bfc2
scenes/spheres_table_far.toml gradients albedo.B=59e42a92276f1ca6
scenes/spheres_table_far.toml gradients albedo.G=a0ffce79ae2e26da
scenes/spheres_table_far.toml gradients albedo.R=98ae98710f2deccf
scenes/spheres_table_far.toml gradients depth.Z=c654d3fe05287b31
scenes/spheres_table_far.toml gradients grad.cdv.Y=dfb9a2d859fdf65e
scenes/spheres_table_far.toml gradients grad.cv.Y=8f96419e5fae73b4
scenes/spheres_table_far.toml gradients grad.dv.Y=bbca6d8e11af1ca8
scenes/spheres_table_far.toml gradients grad.indirect.Y=1af19b15a175cc1b
scenes/spheres_table_far.toml gradients grad.ratio.Y=c32eb5833805216d
scenes/spheres_table_far.toml gradients grad.sv.Y=07e02c2c6f5ad579
scenes/spheres_table_far.toml gradients grad.u.B=3f3bf7bd3ff43240
scenes/spheres_table_far.toml gradients grad.u.G=1e25d4fc53bca589
scenes/spheres_table_far.toml gradients grad.u.R=e385a3d2c1643ec3
scenes/spheres_table_far.toml gradients grad.v.B=c4e9fec8929a7daf
scenes/spheres_table_far.toml gradients grad.v.G=ba9ed3f99ae8d387
scenes/spheres_table_far.toml gradients grad.v.R=6a50559b87ce3daa
scenes/spheres_table_far.toml gradients grad.vis.Y=d5456dae25a03bdb
scenes/spheres_table_far.toml gradients normal.X=36b2c8c01db5115b
scenes/spheres_table_far.toml gradients normal.Y=3bd6e75721f15fd7
scenes/spheres_table_far.toml gradients normal.Z=2fbf8d3c2e020bc0
scenes/spheres_table_far.toml gradients object.id=b25d66d3a2238c85
scenes/spheres_table_far.toml gradients variance.B=9286a0d6ef2cfa4a
scenes/spheres_table_far.toml gradients variance.G=7711ce682a500ae4
scenes/spheres_table_far.toml gradients variance.R=01b1b3d5f3726ca2
scenes/spheres_table_far.toml strategy-gradient B=ff69662b873d0f3f
scenes/spheres_table_far.toml strategy-gradient G=1147938ed8b6e8e2
scenes/spheres_table_far.toml strategy-gradient R=70312e3dd82e8bb9
scenes/spheres_table_far.toml strategy-gradient albedo.B=d6359a6ac508356d
scenes/spheres_table_far.toml strategy-gradient albedo.G=510fc67fd5869831
scenes/spheres_table_far.toml strategy-gradient albedo.R=43818e9a6c8ecb6c
scenes/spheres_table_far.toml strategy-gradient depth.Z=87a8c99f8f89b06e
scenes/spheres_table_far.toml strategy-gradient normal.X=b42cd495d305cf4a
scenes/spheres_table_far.toml strategy-gradient normal.Y=17740a74e189ec07
scenes/spheres_table_far.toml strategy-gradient normal.Z=e169ea7253b99c9c
scenes/spheres_table_far.toml strategy-gradient object.id=b25d66d3a2238c85
scenes/spheres_table_far.toml strategy-gradient samples.Y=79899750a8647405
scenes/spheres_table_far.toml strategy-gradient samples.density=92df35f69dff71e5
scenes/spheres_table_far.toml strategy-variance-linear B=e476d33f7120adbc
scenes/spheres_table_far.toml strategy-variance-linear G=01668881b277ec11
scenes/spheres_table_far.toml strategy-variance-linear R=f7f9820e18afe100
scenes/spheres_table_far.toml strategy-variance-linear albedo.B=d6359a6ac508356d
scenes/spheres_table_far.toml strategy-variance-linear albedo.G=510fc67fd5869831
scenes/spheres_table_far.toml strategy-variance-linear albedo.R=43818e9a6c8ecb6c
scenes/spheres_table_far.toml strategy-variance-linear depth.Z=87a8c99f8f89b06e
scenes/spheres_table_far.toml strategy-variance-linear normal.X=b42cd495d305cf4a
scenes/spheres_table_far.toml strategy-variance-linear normal.Y=17740a74e189ec07
scenes/spheres_table_far.toml strategy-variance-linear normal.Z=e169ea7253b99c9c
scenes/spheres_table_far.toml strategy-variance-linear object.id=b25d66d3a2238c85
scenes/spheres_table_far.toml strategy-variance-linear samples.Y=f317f4c771d63af8
scenes/spheres_table_far.toml strategy-variance-linear samples.density=afe0dfc70c565bc5
scenes/three_spheres_env.toml path B=d2fd48294d88e07b
scenes/three_spheres_env.toml path G=2f60cf08736e3bd8
scenes/three_spheres_env.toml path R=a6ead7220bdcf791
scenes/three_spheres_env.toml path albedo.B=cf64684384636928
scenes/three_spheres_env.toml path albedo.G=c651930249191c32
scenes/three_spheres_env.toml path albedo.R=f4296b7ec4f80764
scenes/three_spheres_env.toml path depth.Z=bc6ef5d9a5473b2a
scenes/three_spheres_env.toml path normal.X=c708d99558d7f1f6
scenes/three_spheres_env.toml path normal.Y=54ff37e900aaa2d8
scenes/three_spheres_env.toml path normal.Z=fe78208c30900722
scenes/three_spheres_env.toml path object.id=38488cf4972a7988
scenes/three_spheres_env.toml path variance.B=edcbcd9cdbb1fe02
scenes/three_spheres_env.toml path variance.G=e5b4324c7ec3f3fa
scenes/three_spheres_env.toml path variance.R=0c3694d9b5832ac5
scenes/three_spheres_env.toml direct B=5803d438851245a2
scenes/three_spheres_env.toml direct G=5ac499ac96eaca70
scenes/three_spheres_env.toml direct R=fb10c8a62871fe9c
scenes/three_spheres_env.toml direct albedo.B=cf64684384636928
scenes/three_spheres_env.toml direct albedo.G=c651930249191c32
scenes/three_spheres_env.toml direct albedo.R=f4296b7ec4f80764
scenes/three_spheres_env.toml direct depth.Z=bc6ef5d9a5473b2a
scenes/three_spheres_env.toml direct normal.X=c708d99558d7f1f6
scenes/three_spheres_env.toml direct normal.Y=54ff37e900aaa2d8
scenes/three_spheres_env.toml direct normal.Z=fe78208c30900722
scenes/three_spheres_env.toml direct object.id=38488cf4972a7988
scenes/three_spheres_env.toml direct variance.B=77dc02f3a8af7d5f
scenes/three_spheres_env.toml direct variance.G=14d6bc1f56529730
scenes/three_spheres_env.toml direct variance.R=93e52c66d3f9d1aa
scenes/three_spheres_env.toml gradients B=7eafaf7e2c16f098
scenes/three_spheres_env.toml gradients G=7d38f9139ef79b76
scenes/three_spheres_env.toml gradients R=17d3709c2e769027
scenes/three_spheres_env.toml gradients albedo.B=cf64684384636928
scenes/three_spheres_env.toml gradients albedo.G=c651930249191c32
scenes/three_spheres_env.toml gradients albedo.R=f4296b7ec4f80764
scenes/three_spheres_env.toml gradients depth.Z=bc6ef5d9a5473b2a
scenes/three_spheres_env.toml gradients grad.cdv.Y=44f03a010bdbfa59
scenes/three_spheres_env.toml gradients grad.cv.Y=c78bf2758da2449d
scenes/three_spheres_env.toml gradients grad.dv.Y=d0549f149dd63a25
scenes/three_spheres_env.toml gradients grad.indirect.Y=409de1079c60e822
scenes/three_spheres_env.toml gradients grad.ratio.Y=e3d2266d1663e51c
scenes/three_spheres_env.toml gradients grad.sv.Y=d0549f149dd63a25
scenes/three_spheres_env.toml gradients grad.u.B=1bd1305c508b5d9e
scenes/three_spheres_env.toml gradients grad.u.G=cb498b09b8a2dd93
scenes/three_spheres_env.toml gradients grad.u.R=d7581dfef7803429
scenes/three_spheres_env.toml gradients grad.v.B=a97f62e2076beb8d
scenes/three_spheres_env.toml gradients grad.v.G=88195775f8bd1105
scenes/three_spheres_env.toml gradients grad.v.R=8e84d94243222a58
scenes/three_spheres_env.toml gradients grad.vis.Y=9243577cda9f3e70
scenes/three_spheres_env.toml gradients normal.X=c708d99558d7f1f6
scenes/three_spheres_env.toml gradients normal.Y=54ff37e900aaa2d8
scenes/three_spheres_env.toml gradients normal.Z=fe78208c30900722
scenes/three_spheres_env.toml gradients object.id=38488cf4972a7988
scenes/three_spheres_env.toml gradients variance.B=01ca2921b5234342
scenes/three_spheres_env.toml gradients variance.G=165083c49885cf39
scenes/three_spheres_env.toml gradients variance.R=ed9c842fd3fd8c32
scenes/three_spheres_env.toml strategy-gradient B=ab3b7a5df4d360ce
scenes/three_spheres_env.toml strategy-gradient G=3d6d3025a31329ee
scenes/three_spheres_env.toml strategy-gradient R=6fb163b4075fd4fb
scenes/three_spheres_env.toml strategy-gradient albedo.B=f856aebfa48a2fc1
scenes/three_spheres_env.toml strategy-gradient albedo.G=9eb61614ecaa4ae1
scenes/three_spheres_env.toml strategy-gradient albedo.R=2d3f15a43b90e6ed
scenes/three_spheres_env.toml strategy-gradient depth.Z=fcf18d79621ecf88
scenes/three_spheres_env.toml strategy-gradient normal.X=87582f98052b9793
scenes/three_spheres_env.toml strategy-gradient normal.Y=e2a6182cc3e93ade
scenes/three_spheres_env.toml strategy-gradient normal.Z=6c08cb0b48c82361
scenes/three_spheres_env.toml strategy-gradient object.id=38488cf4972a7988
scenes/three_spheres_env.toml strategy-gradient samples.Y=f1aae713b814eb75
scenes/three_spheres_env.toml strategy-gradient samples.density=a9ad2cbfa1cf37a5
scenes/three_spheres_env.toml strategy-variance-linear B=4c593f09f0329e78
scenes/three_spheres_env.toml strategy-variance-linear G=1ec348f485733b6e
scenes/three_spheres_env.toml strategy-variance-linear R=5bdec179cc3ff06f
scenes/three_spheres_env.toml strategy-variance-linear albedo.B=f856aebfa48a2fc1
scenes/three_spheres_env.toml strategy-variance-linear albedo.G=9eb61614ecaa4ae1
scenes/three_spheres_env.toml strategy-variance-linear albedo.R=2d3f15a43b90e6ed
scenes/three_spheres_env.toml strategy-variance-linear depth.Z=fcf18d79621ecf88
scenes/three_spheres_env.toml strategy-variance-linear normal.X=87582f98052b9793
scenes/three_spheres_env.toml strategy-variance-linear normal.Y=e2a6182cc3e93ade
scenes/three_spheres_env.toml strategy-variance-linear normal.Z=6c08cb0b48c82361
scenes/three_spheres_env.toml strategy-variance-linear object.id=38488cf4972a7988
scenes/three_spheres_env.toml strategy-variance-linear samples.Y=a7b45ddd39d01b35
scenes/three_spheres_env.toml strategy-variance-linear samples.density=19562ad4fd76e4e5
scenes/objects_bumpy.toml path B=e21af58ed7537e8e
scenes/objects_bumpy.toml path G=91e484419a47ca49
scenes/objects_bumpy.toml path R=2e3b0f10af77b71b
scenes/objects_bumpy.toml path albedo.B=a4c4ad77652f36d9
scenes/objects_bumpy.toml path albedo.G=65549d55bea7f05b
scenes/objects_bumpy.toml path albedo.R=6f4e50ec45db2412
scenes/objects_bumpy.toml path depth.Z=7ba6aa91c5b881f6
scenes/objects_bumpy.toml path normal.X=09607217e1e59704
scenes/objects_bumpy.toml path normal.Y=8b378a27bc47df6c
scenes/objects_bumpy.toml path normal.Z=189f584810a7fa50
scenes/objects_bumpy.toml path object.id=6902b2516b8ed7b5
scenes/objects_bumpy.toml path variance.B=2ede5d3355662b4c
scenes/objects_bumpy.toml path variance.G=48d99a2dcd891b7d
scenes/objects_bumpy.toml path variance.R=e6222219ca94df00
scenes/objects_bumpy.toml direct B=145947dad8f6c090
scenes/objects_bumpy.toml direct G=b17054b280c70e45
scenes/objects_bumpy.toml direct R=01a9b5a9eb1362b8
scenes/objects_bumpy.toml direct albedo.B=a4c4ad77652f36d9
scenes/objects_bumpy.toml direct albedo.G=65549d55bea7f05b
scenes/objects_bumpy.toml direct albedo.R=6f4e50ec45db2412
scenes/objects_bumpy.toml direct depth.Z=7ba6aa91c5b881f6
scenes/objects_bumpy.toml direct normal.X=09607217e1e59704
scenes/objects_bumpy.toml direct normal.Y=8b378a27bc47df6c
scenes/objects_bumpy.toml direct normal.Z=189f584810a7fa50
scenes/objects_bumpy.toml direct object.id=6902b2516b8ed7b5
scenes/objects_bumpy.toml direct variance.B=771025425cde6060
scenes/objects_bumpy.toml direct variance.G=fd881b88d3c180b8
scenes/objects_bumpy.toml direct variance.R=7d887f6481ef2279
scenes/objects_bumpy.toml gradients B=e1a4e594fb44bffa
scenes/objects_bumpy.toml gradients G=de745ad212cba411
scenes/objects_bumpy.toml gradients R=98c6495016a12ed3
scenes/objects_bumpy.toml gradients albedo.B=a4c4ad77652f36d9
scenes/objects_bumpy.toml gradients albedo.G=65549d55bea7f05b
scenes/objects_bumpy.toml gradients albedo.R=6f4e50ec45db2412
scenes/objects_bumpy.toml gradients depth.Z=7ba6aa91c5b881f6
scenes/objects_bumpy.toml gradients grad.cdv.Y=6c6708244a746fb3
scenes/objects_bumpy.toml gradients grad.cv.Y=4ab703ac8f64bc8d
scenes/objects_bumpy.toml gradients grad.dv.Y=331119cbf766386d
scenes/objects_bumpy.toml gradients grad.indirect.Y=82529e9212c0f1e8
scenes/objects_bumpy.toml gradients grad.ratio.Y=ee3c8d1042e70b29
scenes/objects_bumpy.toml gradients grad.sv.Y=c0dd1d55b88eb61a
scenes/objects_bumpy.toml gradients grad.u.B=021095959ff27267
scenes/objects_bumpy.toml gradients grad.u.G=07e4607efd4fb21a
scenes/objects_bumpy.toml gradients grad.u.R=34966a9a3b604461
scenes/objects_bumpy.toml gradients grad.v.B=908d5ad19df408df
scenes/objects_bumpy.toml gradients grad.v.G=e44a902b63932e42
scenes/objects_bumpy.toml gradients grad.v.R=c4a41de3f7a03458
scenes/objects_bumpy.toml gradients grad.vis.Y=ed4898a74f10c16e
scenes/objects_bumpy.toml gradients normal.X=09607217e1e59704
scenes/objects_bumpy.toml gradients normal.Y=8b378a27bc47df6c
scenes/objects_bumpy.toml gradients normal.Z=189f584810a7fa50
scenes/objects_bumpy.toml gradients object.id=6902b2516b8ed7b5
scenes/objects_bumpy.toml gradients variance.B=c5f5946794626659
scenes/objects_bumpy.toml gradients variance.G=cd069eb921c21654
scenes/objects_bumpy.toml gradients variance.R=33f4fc69bb6d4922
scenes/objects_bumpy.toml strategy-gradient B=29645670efb94a01
scenes/objects_bumpy.toml strategy-gradient G=d1756f9c5bf40283
scenes/objects_bumpy.toml strategy-gradient R=56d7dd054d50143f
scenes/objects_bumpy.toml strategy-gradient albedo.B=76e7a314fcd21469
scenes/objects_bumpy.toml strategy-gradient albedo.G=faf6b9fe67349511
scenes/objects_bumpy.toml strategy-gradient albedo.R=ebb24245d65aaa49
scenes/objects_bumpy.toml strategy-gradient depth.Z=6ee85b342a0e7359
scenes/objects_bumpy.toml strategy-gradient normal.X=217af88ecb452a99
scenes/objects_bumpy.toml strategy-gradient normal.Y=895fce9087c288df
scenes/objects_bumpy.toml strategy-gradient normal.Z=b1f50bf711f2087b
scenes/objects_bumpy.toml strategy-gradient object.id=6902b2516b8ed7b5
scenes/objects_bumpy.toml strategy-gradient samples.Y=3e8dc86de3428d45
scenes/objects_bumpy.toml strategy-gradient samples.density=896e45cf7f23dc38
scenes/objects_bumpy.toml strategy-variance-linear B=108319f3c62e6158
scenes/objects_bumpy.toml strategy-variance-linear G=61b025fd7e916a1b
scenes/objects_bumpy.toml strategy-variance-linear R=1ce906e325c41252
scenes/objects_bumpy.toml strategy-variance-linear albedo.B=76e7a314fcd21469
scenes/objects_bumpy.toml strategy-variance-linear albedo.G=faf6b9fe67349511
scenes/objects_bumpy.toml strategy-variance-linear albedo.R=ebb24245d65aaa49
scenes/objects_bumpy.toml strategy-variance-linear depth.Z=6ee85b342a0e7359
scenes/objects_bumpy.toml strategy-variance-linear normal.X=217af88ecb452a99
scenes/objects_bumpy.toml strategy-variance-linear normal.Y=895fce9087c288df
scenes/objects_bumpy.toml strategy-variance-linear normal.Z=b1f50bf711f2087b
scenes/objects_bumpy.toml strategy-variance-linear object.id=6902b2516b8ed7b5
scenes/objects_bumpy.toml strategy-variance-linear samples.Y=cc72c4cea5a50e18
scenes/objects_bumpy.toml strategy-variance-linear samples.density=973eca0879b6dc45
scenes/bunny_env.toml path B=a1767f019e56926d
scenes/bunny_env.toml path G=cb7771b390f568c1
scenes/bunny_env.toml path R=ce4d89c83aed2b32
scenes/bunny_env.toml path albedo.B=bcc7e64107833977
scenes/bunny_env.toml path albedo.G=a400216c916bff6f
scenes/bunny_env.toml path albedo.R=2aea46c24c133246
scenes/bunny_env.toml path depth.Z=6bba4619ddafd4b0
scenes/bunny_env.toml path normal.X=649ea091c0d0fcb7
scenes/bunny_env.toml path normal.Y=79db0df63c6615de
scenes/bunny_env.toml path normal.Z=453f751b0e3fa4b9
scenes/bunny_env.toml path object.id=a487430f181d2238
scenes/bunny_env.toml path variance.B=3001bd1b19ca0bcd
scenes/bunny_env.toml path variance.G=0d5ef01852cbe885
scenes/bunny_env.toml path variance.R=618369efd3cf2b67
scenes/bunny_env.toml direct B=34ec91cc2fd1cb33
scenes/bunny_env.toml direct G=85a5a96ebfaf3c63
scenes/bunny_env.toml direct R=5f2eccb31c9aa1ef
scenes/bunny_env.toml direct albedo.B=bcc7e64107833977
scenes/bunny_env.toml direct albedo.G=a400216c916bff6f
scenes/bunny_env.toml direct albedo.R=2aea46c24c133246
scenes/bunny_env.toml direct depth.Z=6bba4619ddafd4b0
scenes/bunny_env.toml direct normal.X=649ea091c0d0fcb7
scenes/bunny_env.toml direct normal.Y=79db0df63c6615de
scenes/bunny_env.toml direct normal.Z=453f751b0e3fa4b9
scenes/bunny_env.toml direct object.id=a487430f181d2238
scenes/bunny_env.toml direct variance.B=777d6f336991befb
scenes/bunny_env.toml direct variance.G=de397f0b758fddc5
scenes/bunny_env.toml direct variance.R=484115d270ddf1d7
scenes/bunny_env.toml gradients B=3892d696a0825e76
scenes/bunny_env.toml gradients G=849819157012a0cc
scenes/bunny_env.toml gradients R=16d35e3ec907e849
scenes/bunny_env.toml gradients albedo.B=bcc7e64107833977
scenes/bunny_env.toml gradients albedo.G=a400216c916bff6f
scenes/bunny_env.toml gradients albedo.R=2aea46c24c133246
scenes/bunny_env.toml gradients depth.Z=6bba4619ddafd4b0
scenes/bunny_env.toml gradients grad.cdv.Y=76cfd17857fff528
scenes/bunny_env.toml gradients grad.cv.Y=e6385258253af167
scenes/bunny_env.toml gradients grad.dv.Y=f616970a5167d562
scenes/bunny_env.toml gradients grad.indirect.Y=525f6639671a0af6
scenes/bunny_env.toml gradients grad.ratio.Y=5c54df530f2d8620
scenes/bunny_env.toml gradients grad.sv.Y=43866fff616df80f
scenes/bunny_env.toml gradients grad.u.B=36a61a2b89e238ed
scenes/bunny_env.toml gradients grad.u.G=38989b884a38dcce
scenes/bunny_env.toml gradients grad.u.R=1f5c5502d6c52152
scenes/bunny_env.toml gradients grad.v.B=1053472a16f55dfe
scenes/bunny_env.toml gradients grad.v.G=d1240f4ada717ecc
scenes/bunny_env.toml gradients grad.v.R=ae3a913955538f6a
scenes/bunny_env.toml gradients grad.vis.Y=1b16f0a56c9fa68f
scenes/bunny_env.toml gradients normal.X=649ea091c0d0fcb7
scenes/bunny_env.toml gradients normal.Y=79db0df63c6615de
scenes/bunny_env.toml gradients normal.Z=453f751b0e3fa4b9
scenes/bunny_env.toml gradients object.id=a487430f181d2238
scenes/bunny_env.toml gradients variance.B=94e1f2502a1489ba
scenes/bunny_env.toml gradients variance.G=8277646f3c9e5592
scenes/bunny_env.toml gradients variance.R=b5a249d64fcd8089
scenes/bunny_env.toml strategy-gradient B=54895d55032076b2
scenes/bunny_env.toml strategy-gradient G=7ecc7ee90e455409
scenes/bunny_env.toml strategy-gradient R=8da8c1f05d6ee85e
scenes/bunny_env.toml strategy-gradient albedo.B=5106fb12843fe6b0
scenes/bunny_env.toml strategy-gradient albedo.G=53d0adf4eb6551e8
scenes/bunny_env.toml strategy-gradient albedo.R=d6d69b8e869b23f4
scenes/bunny_env.toml strategy-gradient depth.Z=27e756faaf7319ce
scenes/bunny_env.toml strategy-gradient normal.X=f34bd463ad4c9a22
scenes/bunny_env.toml strategy-gradient normal.Y=6401af552601f33c
scenes/bunny_env.toml strategy-gradient normal.Z=9e31e98c1b386d16
scenes/bunny_env.toml strategy-gradient object.id=a487430f181d2238
scenes/bunny_env.toml strategy-gradient samples.Y=332d92b0c61747e5
scenes/bunny_env.toml strategy-gradient samples.density=4cc881e2ea1f8d25
scenes/bunny_env.toml strategy-variance-linear B=64ee85bbd46141d1
scenes/bunny_env.toml strategy-variance-linear G=3fe116710a3cb8a4
scenes/bunny_env.toml strategy-variance-linear R=c403af10234dadea
scenes/bunny_env.toml strategy-variance-linear albedo.B=5106fb12843fe6b0
scenes/bunny_env.toml strategy-variance-linear albedo.G=53d0adf4eb6551e8
scenes/bunny_env.toml strategy-variance-linear albedo.R=d6d69b8e869b23f4
scenes/bunny_env.toml strategy-variance-linear depth.Z=27e756faaf7319ce
scenes/bunny_env.toml strategy-variance-linear normal.X=f34bd463ad4c9a22
scenes/bunny_env.toml strategy-variance-linear normal.Y=6401af552601f33c
scenes/bunny_env.toml strategy-variance-linear normal.Z=9e31e98c1b386d16
scenes/bunny_env.toml strategy-variance-linear object.id=a487430f181d2238
scenes/bunny_env.toml strategy-variance-linear samples.Y=88bcf3f900d01675
scenes/bunny_env.toml strategy-variance-linear samples.density=54b55e371690cf45
scenes/validation/cornell.toml path B=df019465e70cc7fe
scenes/validation/cornell.toml path G=c67ff8b24d957d54
scenes/validation/cornell.toml path R=9214053d4d8af7ec
scenes/validation/cornell.toml path albedo.B=1cf114732f212c55
scenes/validation/cornell.toml path albedo.G=c2e25bc731600b34
scenes/validation/cornell.toml path albedo.R=bd8f4061c03a3b1e
scenes/validation/cornell.toml path depth.Z=290bd36927a50f83
scenes/validation/cornell.toml path normal.X=31f3ca84306f0094
scenes/validation/cornell.toml path normal.Y=8c1187f9ae3c9dd5
scenes/validation/cornell.toml path normal.Z=aae88a9e55e38b01
scenes/validation/cornell.toml path object.id=7e33a05ceaa17428
scenes/validation/cornell.toml path variance.B=760da47536954266
scenes/validation/cornell.toml path variance.G=8a85847ef4953b6b
scenes/validation/cornell.toml path variance.R=d5262911a5df027e
scenes/validation/cornell.toml direct B=c1ab1847e8d05a81
scenes/validation/cornell.toml direct G=8cacd8bd38520972
scenes/validation/cornell.toml direct R=1efc3f5311fc2665
scenes/validation/cornell.toml direct albedo.B=1cf114732f212c55
scenes/validation/cornell.toml direct albedo.G=c2e25bc731600b34
scenes/validation/cornell.toml direct albedo.R=bd8f4061c03a3b1e
scenes/validation/cornell.toml direct depth.Z=290bd36927a50f83
scenes/validation/cornell.toml direct normal.X=31f3ca84306f0094
scenes/validation/cornell.toml direct normal.Y=8c1187f9ae3c9dd5
scenes/validation/cornell.toml direct normal.Z=aae88a9e55e38b01
scenes/validation/cornell.toml direct object.id=7e33a05ceaa17428
scenes/validation/cornell.toml direct variance.B=d117b3a0e16391d8
scenes/validation/cornell.toml direct variance.G=4528e052b2ac81ba
scenes/validation/cornell.toml direct variance.R=632339f341b3776a
scenes/validation/cornell.toml gradients B=a2b719a061963f47
scenes/validation/cornell.toml gradients G=70937407e8d44d58
scenes/validation/cornell.toml gradients R=0fdc10db003cce79
scenes/validation/cornell.toml gradients albedo.B=1cf114732f212c55
scenes/validation/cornell.toml gradients albedo.G=c2e25bc731600b34
scenes/validation/cornell.toml gradients albedo.R=bd8f4061c03a3b1e
scenes/validation/cornell.toml gradients depth.Z=290bd36927a50f83
scenes/validation/cornell.toml gradients grad.cdv.Y=d0549f149dd63a25
scenes/validation/cornell.toml gradients grad.cv.Y=d0549f149dd63a25
scenes/validation/cornell.toml gradients grad.dv.Y=d0549f149dd63a25
scenes/validation/cornell.toml gradients grad.indirect.Y=d0549f149dd63a25
scenes/validation/cornell.toml gradients grad.ratio.Y=d0549f149dd63a25
scenes/validation/cornell.toml gradients grad.sv.Y=17e2307b74bba55d
scenes/validation/cornell.toml gradients grad.u.B=8f49fbaaca6ef21c
scenes/validation/cornell.toml gradients grad.u.G=450080b9ccf3af14
scenes/validation/cornell.toml gradients grad.u.R=162c22e2078f16d3
scenes/validation/cornell.toml gradients grad.v.B=0973021f68c017a4
scenes/validation/cornell.toml gradients grad.v.G=157903b744d62078
scenes/validation/cornell.toml gradients grad.v.R=7ae704fa36e65779
scenes/validation/cornell.toml gradients grad.vis.Y=a72f6f8de8dd13f6
scenes/validation/cornell.toml gradients normal.X=31f3ca84306f0094
scenes/validation/cornell.toml gradients normal.Y=8c1187f9ae3c9dd5
scenes/validation/cornell.toml gradients normal.Z=aae88a9e55e38b01
scenes/validation/cornell.toml gradients object.id=7e33a05ceaa17428
scenes/validation/cornell.toml gradients variance.B=3b63e0e073a61c97
scenes/validation/cornell.toml gradients variance.G=9997cefdc5ec9060
scenes/validation/cornell.toml gradients variance.R=a1937b455142ff38
scenes/validation/cornell.toml strategy-gradient B=a58338495abdeac1
scenes/validation/cornell.toml strategy-gradient G=f319f79e85b31a1c
scenes/validation/cornell.toml strategy-gradient R=710448ef912261fc
scenes/validation/cornell.toml strategy-gradient albedo.B=b0d7f7c8e3a1d98c
scenes/validation/cornell.toml strategy-gradient albedo.G=a6e5f6bec7d3e956
scenes/validation/cornell.toml strategy-gradient albedo.R=bc2325996af6d5c1
scenes/validation/cornell.toml strategy-gradient depth.Z=bdd7108921219a97
scenes/validation/cornell.toml strategy-gradient normal.X=9b92fa7bea1bb0ca
scenes/validation/cornell.toml strategy-gradient normal.Y=e23462326f60e135
scenes/validation/cornell.toml strategy-gradient normal.Z=95fcda116dc4bf6b
scenes/validation/cornell.toml strategy-gradient object.id=7e33a05ceaa17428
scenes/validation/cornell.toml strategy-gradient samples.Y=7a17020687504415
scenes/validation/cornell.toml strategy-gradient samples.density=f34091662da53b65
scenes/validation/cornell.toml strategy-variance-linear B=36fc18ade71dd614
scenes/validation/cornell.toml strategy-variance-linear G=a79e15999d60d306
scenes/validation/cornell.toml strategy-variance-linear R=9530a8a03622ea51
scenes/validation/cornell.toml strategy-variance-linear albedo.B=b0d7f7c8e3a1d98c
scenes/validation/cornell.toml strategy-variance-linear albedo.G=a6e5f6bec7d3e956
scenes/validation/cornell.toml strategy-variance-linear albedo.R=bc2325996af6d5c1
scenes/validation/cornell.toml strategy-variance-linear depth.Z=bdd7108921219a97
scenes/validation/cornell.toml strategy-variance-linear normal.X=9b92fa7bea1bb0ca
scenes/validation/cornell.toml strategy-variance-linear normal.Y=e23462326f60e135
scenes/validation/cornell.toml strategy-variance-linear normal.Z=95fcda116dc4bf6b
scenes/validation/cornell.toml strategy-variance-linear object.id=7e33a05ceaa17428
scenes/validation/cornell.toml strategy-variance-linear samples.Y=98ef037065239ff8
scenes/validation/cornell.toml strategy-variance-linear samples.density=cc0a1171ab730745
scenes/validation/env_constant.toml path B=1785484a8acbea17
scenes/validation/env_constant.toml path G=469d62b14a540012
scenes/validation/env_constant.toml path R=8240f9756e15bbbc
scenes/validation/env_constant.toml path albedo.B=173bc8a7db50d99b
scenes/validation/env_constant.toml path albedo.G=bc6b4d2c19590cdf
scenes/validation/env_constant.toml path albedo.R=b14346836f7cc88e
scenes/validation/env_constant.toml path depth.Z=36b4192c21ae6043
scenes/validation/env_constant.toml path normal.X=9f01fa2ada0b0b8d
scenes/validation/env_constant.toml path normal.Y=8cbad9aeaee6837d
scenes/validation/env_constant.toml path normal.Z=fd8987a46589795f
scenes/validation/env_constant.toml path object.id=07fdd23b984a4dc5
scenes/validation/env_constant.toml path variance.B=33cabce35ad45426
scenes/validation/env_constant.toml path variance.G=396d418807eabd70
scenes/validation/env_constant.toml path variance.R=24117f3b2505bbbe
scenes/validation/env_constant.toml direct B=3389b5e1a6308654
scenes/validation/env_constant.toml direct G=91a9e9083692eb96
scenes/validation/env_constant.toml direct R=a33709a87ab647ed
scenes/validation/env_constant.toml direct albedo.B=173bc8a7db50d99b
scenes/validation/env_constant.toml direct albedo.G=bc6b4d2c19590cdf
scenes/validation/env_constant.toml direct albedo.R=b14346836f7cc88e
scenes/validation/env_constant.toml direct depth.Z=36b4192c21ae6043
scenes/validation/env_constant.toml direct normal.X=9f01fa2ada0b0b8d
scenes/validation/env_constant.toml direct normal.Y=8cbad9aeaee6837d
scenes/validation/env_constant.toml direct normal.Z=fd8987a46589795f
scenes/validation/env_constant.toml direct object.id=07fdd23b984a4dc5
scenes/validation/env_constant.toml direct variance.B=a37d60af53e1574c
scenes/validation/env_constant.toml direct variance.G=4e053c6662195bf2
scenes/validation/env_constant.toml direct variance.R=4ee5e38c28c8457e
scenes/validation/env_constant.toml gradients B=780a776a9b10c8ea
scenes/validation/env_constant.toml gradients G=999a43c74f187833
scenes/validation/env_constant.toml gradients R=f63130bd7ee12f52
scenes/validation/env_constant.toml gradients albedo.B=173bc8a7db50d99b
scenes/validation/env_constant.toml gradients albedo.G=bc6b4d2c19590cdf
scenes/validation/env_constant.toml gradients albedo.R=b14346836f7cc88e
scenes/validation/env_constant.toml gradients depth.Z=36b4192c21ae6043
scenes/validation/env_constant.toml gradients grad.cdv.Y=8c8ace98c940f4a0
scenes/validation/env_constant.toml gradients grad.cv.Y=c1d02651c798474c
scenes/validation/env_constant.toml gradients grad.dv.Y=d0549f149dd63a25
scenes/validation/env_constant.toml gradients grad.indirect.Y=8aa2e514d2c6c212
scenes/validation/env_constant.toml gradients grad.ratio.Y=f28589d7818c3fec
scenes/validation/env_constant.toml gradients grad.sv.Y=d0549f149dd63a25
scenes/validation/env_constant.toml gradients grad.u.B=2fa9e7c107a4b100
scenes/validation/env_constant.toml gradients grad.u.G=a27092e8a760d975
scenes/validation/env_constant.toml gradients grad.u.R=ebcbafeef97a3e09
scenes/validation/env_constant.toml gradients grad.v.B=22d1064bc39bf7f0
scenes/validation/env_constant.toml gradients grad.v.G=cd45603cbc6e167f
scenes/validation/env_constant.toml gradients grad.v.R=98d566f548ff8d86
scenes/validation/env_constant.toml gradients grad.vis.Y=3ffea905592aa345
scenes/validation/env_constant.toml gradients normal.X=9f01fa2ada0b0b8d
scenes/validation/env_constant.toml gradients normal.Y=8cbad9aeaee6837d
scenes/validation/env_constant.toml gradients normal.Z=fd8987a46589795f
scenes/validation/env_constant.toml gradients object.id=07fdd23b984a4dc5
scenes/validation/env_constant.toml gradients variance.B=113d6a951ebe4eb2
scenes/validation/env_constant.toml gradients variance.G=1ac79fd37837e74f
scenes/validation/env_constant.toml gradients variance.R=2e40b7bb21edc025
scenes/validation/env_constant.toml strategy-gradient B=c880857899b4b096
scenes/validation/env_constant.toml strategy-gradient G=8790c3163af62c83
scenes/validation/env_constant.toml strategy-gradient R=78bf5f4544e14830
scenes/validation/env_constant.toml strategy-gradient albedo.B=3ce9538c48b58955
scenes/validation/env_constant.toml strategy-gradient albedo.G=58c68b3739df3e1d
scenes/validation/env_constant.toml strategy-gradient albedo.R=f3c4ceead17bd7ed
scenes/validation/env_constant.toml strategy-gradient depth.Z=30e72b1bfb56aae8
scenes/validation/env_constant.toml strategy-gradient normal.X=aaef1e1a1bd53052
scenes/validation/env_constant.toml strategy-gradient normal.Y=fad6d3690ddaa8de
scenes/validation/env_constant.toml strategy-gradient normal.Z=ae7d27fec7b79245
scenes/validation/env_constant.toml strategy-gradient object.id=07fdd23b984a4dc5
scenes/validation/env_constant.toml strategy-gradient samples.Y=85c7bc9198fac428
scenes/validation/env_constant.toml strategy-gradient samples.density=7fd011f4c68373a5
scenes/validation/env_constant.toml strategy-variance-linear B=f17c1a22fc620e4c
scenes/validation/env_constant.toml strategy-variance-linear G=a865e6e19373baf6
scenes/validation/env_constant.toml strategy-variance-linear R=66377c8c759b1073
scenes/validation/env_constant.toml strategy-variance-linear albedo.B=3ce9538c48b58955
scenes/validation/env_constant.toml strategy-variance-linear albedo.G=58c68b3739df3e1d
scenes/validation/env_constant.toml strategy-variance-linear albedo.R=f3c4ceead17bd7ed
scenes/validation/env_constant.toml strategy-variance-linear depth.Z=30e72b1bfb56aae8
scenes/validation/env_constant.toml strategy-variance-linear normal.X=aaef1e1a1bd53052
scenes/validation/env_constant.toml strategy-variance-linear normal.Y=fad6d3690ddaa8de
scenes/validation/env_constant.toml strategy-variance-linear normal.Z=ae7d27fec7b79245
scenes/validation/env_constant.toml strategy-variance-linear object.id=07fdd23b984a4dc5
scenes/validation/env_constant.toml strategy-variance-linear samples.Y=fe8bedfca4270e75
scenes/validation/env_constant.toml strategy-variance-linear samples.density=efed94c34ba4bbc5
scenes/validation/env_image.toml path B=5900eec4c3e680a3
scenes/validation/env_image.toml path G=2cf22e4af74ffdbd
scenes/validation/env_image.toml path R=4530a049468f3ac9
scenes/validation/env_image.toml path albedo.B=173bc8a7db50d99b
scenes/validation/env_image.toml path albedo.G=bc6b4d2c19590cdf
scenes/validation/env_image.toml path albedo.R=b14346836f7cc88e
scenes/validation/env_image.toml path depth.Z=36b4192c21ae6043
scenes/validation/env_image.toml path normal.X=9f01fa2ada0b0b8d
scenes/validation/env_image.toml path normal.Y=8cbad9aeaee6837d
scenes/validation/env_image.toml path normal.Z=fd8987a46589795f
scenes/validation/env_image.toml path object.id=07fdd23b984a4dc5
scenes/validation/env_image.toml path variance.B=a61de401a9cfc984
scenes/validation/env_image.toml path variance.G=8aacdbc6e9943a5f
scenes/validation/env_image.toml path variance.R=701b095332a34c91
scenes/validation/env_image.toml direct B=2c51504d59d4d1eb
scenes/validation/env_image.toml direct G=0a4f545f2eecb3aa
scenes/validation/env_image.toml direct R=9b250cba234491bb
scenes/validation/env_image.toml direct albedo.B=173bc8a7db50d99b
scenes/validation/env_image.toml direct albedo.G=bc6b4d2c19590cdf
scenes/validation/env_image.toml direct albedo.R=b14346836f7cc88e
scenes/validation/env_image.toml direct depth.Z=36b4192c21ae6043
scenes/validation/env_image.toml direct normal.X=9f01fa2ada0b0b8d
scenes/validation/env_image.toml direct normal.Y=8cbad9aeaee6837d
scenes/validation/env_image.toml direct normal.Z=fd8987a46589795f
scenes/validation/env_image.toml direct object.id=07fdd23b984a4dc5
scenes/validation/env_image.toml direct variance.B=eb874f76876e4f36
scenes/validation/env_image.toml direct variance.G=9cceaf6e64f8811b
scenes/validation/env_image.toml direct variance.R=c2e171ea5c308bc1
scenes/validation/env_image.toml gradients B=e2029b6d99df90ea
scenes/validation/env_image.toml gradients G=151f93305930b7f7
scenes/validation/env_image.toml gradients R=4c3c74643772ad4a
scenes/validation/env_image.toml gradients albedo.B=173bc8a7db50d99b
scenes/validation/env_image.toml gradients albedo.G=bc6b4d2c19590cdf
scenes/validation/env_image.toml gradients albedo.R=b14346836f7cc88e
scenes/validation/env_image.toml gradients depth.Z=36b4192c21ae6043
scenes/validation/env_image.toml gradients grad.cdv.Y=1df59ea604920bdb
scenes/validation/env_image.toml gradients grad.cv.Y=c1d02651c798474c
scenes/validation/env_image.toml gradients grad.dv.Y=d0549f149dd63a25
scenes/validation/env_image.toml gradients grad.indirect.Y=74070921d0e07c2a
scenes/validation/env_image.toml gradients grad.ratio.Y=7cd86cda533179b1
scenes/validation/env_image.toml gradients grad.sv.Y=d0549f149dd63a25
scenes/validation/env_image.toml gradients grad.u.B=eaab92c104e33be2
scenes/validation/env_image.toml gradients grad.u.G=99c98b39d1b15828
scenes/validation/env_image.toml gradients grad.u.R=dcf5d74b53dbf8c9
scenes/validation/env_image.toml gradients grad.v.B=741a6b6a4d091a77
scenes/validation/env_image.toml gradients grad.v.G=ef06dd9e97a217bb
scenes/validation/env_image.toml gradients grad.v.R=dff7f4f4e73de5fe
scenes/validation/env_image.toml gradients grad.vis.Y=7c976ab425222aca
scenes/validation/env_image.toml gradients normal.X=9f01fa2ada0b0b8d
scenes/validation/env_image.toml gradients normal.Y=8cbad9aeaee6837d
scenes/validation/env_image.toml gradients normal.Z=fd8987a46589795f
scenes/validation/env_image.toml gradients object.id=07fdd23b984a4dc5
scenes/validation/env_image.toml gradients variance.B=8410ed909dec5dd6
scenes/validation/env_image.toml gradients variance.G=ccc6c1cd693755ed
scenes/validation/env_image.toml gradients variance.R=95d5a7b409dd2e3f
scenes/validation/env_image.toml strategy-gradient B=881ff241433132d5
scenes/validation/env_image.toml strategy-gradient G=71de7c5602e653f8
scenes/validation/env_image.toml strategy-gradient R=41a50193f428cd7b
scenes/validation/env_image.toml strategy-gradient albedo.B=3ce9538c48b58955
scenes/validation/env_image.toml strategy-gradient albedo.G=58c68b3739df3e1d
scenes/validation/env_image.toml strategy-gradient albedo.R=f3c4ceead17bd7ed
scenes/validation/env_image.toml strategy-gradient depth.Z=30e72b1bfb56aae8
scenes/validation/env_image.toml strategy-gradient normal.X=aaef1e1a1bd53052
scenes/validation/env_image.toml strategy-gradient normal.Y=fad6d3690ddaa8de
scenes/validation/env_image.toml strategy-gradient normal.Z=ae7d27fec7b79245
scenes/validation/env_image.toml strategy-gradient object.id=07fdd23b984a4dc5
scenes/validation/env_image.toml strategy-gradient samples.Y=4411b2b66f7b37f8
scenes/validation/env_image.toml strategy-gradient samples.density=058246de2cd1a3a5
scenes/validation/env_image.toml strategy-variance-linear B=75f5e518456274b0
scenes/validation/env_image.toml strategy-variance-linear G=a6a0b7b86e6e9216
scenes/validation/env_image.toml strategy-variance-linear R=ed17ce82c3a7a3da
scenes/validation/env_image.toml strategy-variance-linear albedo.B=3ce9538c48b58955
scenes/validation/env_image.toml strategy-variance-linear albedo.G=58c68b3739df3e1d
scenes/validation/env_image.toml strategy-variance-linear albedo.R=f3c4ceead17bd7ed
scenes/validation/env_image.toml strategy-variance-linear depth.Z=30e72b1bfb56aae8
scenes/validation/env_image.toml strategy-variance-linear normal.X=aaef1e1a1bd53052
scenes/validation/env_image.toml strategy-variance-linear normal.Y=fad6d3690ddaa8de
scenes/validation/env_image.toml strategy-variance-linear normal.Z=ae7d27fec7b79245
scenes/validation/env_image.toml strategy-variance-linear object.id=07fdd23b984a4dc5
scenes/validation/env_image.toml strategy-variance-linear samples.Y=8ffc897d3d22e545
scenes/validation/env_image.toml strategy-variance-linear samples.density=d786ee175cadef15
scenes/validation/spheres.toml path B=dd56702aa4b1cd85
scenes/validation/spheres.toml path G=d9be74c64a777399
scenes/validation/spheres.toml path R=e8c4740f0d4901e3
scenes/validation/spheres.toml path albedo.B=af438cfbc474f21c
scenes/validation/spheres.toml path albedo.G=a75d04c335dcfca2
scenes/validation/spheres.toml path albedo.R=e28e7fe8e4049f7b
scenes/validation/spheres.toml path depth.Z=f2b9bdd8356b450b
scenes/validation/spheres.toml path normal.X=46735ae55ae30a42
scenes/validation/spheres.toml path normal.Y=f7a4147889c71013
scenes/validation/spheres.toml path normal.Z=61ae9fb2639d8a5a
scenes/validation/spheres.toml path object.id=e1f7a259153301f5
scenes/validation/spheres.toml path variance.B=66a3624c2bd2a5e3
scenes/validation/spheres.toml path variance.G=c5d5c3d76afaf2d9
scenes/validation/spheres.toml path variance.R=74ddc8283216c97f
scenes/validation/spheres.toml direct B=7f1970095227ae97
scenes/validation/spheres.toml direct G=cf70ed7cf29300da
scenes/validation/spheres.toml direct R=3e389623d8224335
scenes/validation/spheres.toml direct albedo.B=af438cfbc474f21c
scenes/validation/spheres.toml direct albedo.G=a75d04c335dcfca2
scenes/validation/spheres.toml direct albedo.R=e28e7fe8e4049f7b
scenes/validation/spheres.toml direct depth.Z=f2b9bdd8356b450b
scenes/validation/spheres.toml direct normal.X=46735ae55ae30a42
scenes/validation/spheres.toml direct normal.Y=f7a4147889c71013
scenes/validation/spheres.toml direct normal.Z=61ae9fb2639d8a5a
scenes/validation/spheres.toml direct object.id=e1f7a259153301f5
scenes/validation/spheres.toml direct variance.B=9158db3d5ee7a01e
scenes/validation/spheres.toml direct variance.G=c983f801e8cba1e6
scenes/validation/spheres.toml direct variance.R=84ed4a85fd5d6e22
scenes/validation/spheres.toml gradients B=eeae361c1382ec12
scenes/validation/spheres.toml gradients G=0f0661862b411c89
scenes/validation/spheres.toml gradients R=48b2277247f167e6
scenes/validation/spheres.toml gradients albedo.B=af438cfbc474f21c
scenes/validation/spheres.toml gradients albedo.G=a75d04c335dcfca2
scenes/validation/spheres.toml gradients albedo.R=e28e7fe8e4049f7b
scenes/validation/spheres.toml gradients depth.Z=f2b9bdd8356b450b
scenes/validation/spheres.toml gradients grad.cdv.Y=5ffd4433ecc95334
scenes/validation/spheres.toml gradients grad.cv.Y=02b3fa62ca5afa49
scenes/validation/spheres.toml gradients grad.dv.Y=d0549f149dd63a25
scenes/validation/spheres.toml gradients grad.indirect.Y=28a969b9e301afe1
scenes/validation/spheres.toml gradients grad.ratio.Y=b0ad455e444832a2
scenes/validation/spheres.toml gradients grad.sv.Y=e0358c0983f223d4
scenes/validation/spheres.toml gradients grad.u.B=0c74328d1f1ac661
scenes/validation/spheres.toml gradients grad.u.G=f66fd2608a24917d
scenes/validation/spheres.toml gradients grad.u.R=16696917bee11951
scenes/validation/spheres.toml gradients grad.v.B=1dda72e5a2e07a90
scenes/validation/spheres.toml gradients grad.v.G=117ffefadbd1fdfe
scenes/validation/spheres.toml gradients grad.v.R=6e7113d195237a4a
scenes/validation/spheres.toml gradients grad.vis.Y=0ef5ad6f3ab30322
scenes/validation/spheres.toml gradients normal.X=46735ae55ae30a42
scenes/validation/spheres.toml gradients normal.Y=f7a4147889c71013
scenes/validation/spheres.toml gradients normal.Z=61ae9fb2639d8a5a
scenes/validation/spheres.toml gradients object.id=e1f7a259153301f5
scenes/validation/spheres.toml gradients variance.B=2aafe256d1baa4f9
scenes/validation/spheres.toml gradients variance.G=46b99804ca0ef114
scenes/validation/spheres.toml gradients variance.R=be673ed321b062b0
scenes/validation/spheres.toml strategy-gradient B=136e4f75967407a3
scenes/validation/spheres.toml strategy-gradient G=c7d36da19859f448
scenes/validation/spheres.toml strategy-gradient R=600a00a385c8d70d
scenes/validation/spheres.toml strategy-gradient albedo.B=c01b947d672c8a6d
scenes/validation/spheres.toml strategy-gradient albedo.G=ce9c0cfba9d4a355
scenes/validation/spheres.toml strategy-gradient albedo.R=1f1788370415d195
scenes/validation/spheres.toml strategy-gradient depth.Z=911476ee6e534e3e
scenes/validation/spheres.toml strategy-gradient normal.X=5c8a08bfe5f256e2
scenes/validation/spheres.toml strategy-gradient normal.Y=5f7baaa5b890e9d4
scenes/validation/spheres.toml strategy-gradient normal.Z=edd36d30a1a07d8f
scenes/validation/spheres.toml strategy-gradient object.id=e1f7a259153301f5
scenes/validation/spheres.toml strategy-gradient samples.Y=7f00b00cb0d0d745
scenes/validation/spheres.toml strategy-gradient samples.density=3549866057c7cd45
scenes/validation/spheres.toml strategy-variance-linear B=588f63d55992c7bb
scenes/validation/spheres.toml strategy-variance-linear G=e0cfebd5d2312f51
scenes/validation/spheres.toml strategy-variance-linear R=ff52291293dc4b69
scenes/validation/spheres.toml strategy-variance-linear albedo.B=c01b947d672c8a6d
scenes/validation/spheres.toml strategy-variance-linear albedo.G=ce9c0cfba9d4a355
scenes/validation/spheres.toml strategy-variance-linear albedo.R=1f1788370415d195
scenes/validation/spheres.toml strategy-variance-linear depth.Z=911476ee6e534e3e
scenes/validation/spheres.toml strategy-variance-linear normal.X=5c8a08bfe5f256e2
scenes/validation/spheres.toml strategy-variance-linear normal.Y=5f7baaa5b890e9d4
scenes/validation/spheres.toml strategy-variance-linear normal.Z=edd36d30a1a07d8f
scenes/validation/spheres.toml strategy-variance-linear object.id=e1f7a259153301f5
scenes/validation/spheres.toml strategy-variance-linear samples.Y=8291432f3e5324f8
scenes/validation/spheres.toml strategy-variance-linear samples.density=85e3935d59daecf5";
