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
scenes/cornell.toml strategy-gradient B=4f88f9e33ac4b91c
scenes/cornell.toml strategy-gradient G=2031818ceb7af74a
scenes/cornell.toml strategy-gradient R=bf452350b3ff91bb
scenes/cornell.toml strategy-gradient samples.Y=493dc5d27d7b3ef5
scenes/cornell.toml strategy-gradient samples.density=b58d5ca1b0e525e5
scenes/cornell.toml strategy-variance-linear B=ee1d2b3ad4a227ae
scenes/cornell.toml strategy-variance-linear G=ed901b5e0a83ab2b
scenes/cornell.toml strategy-variance-linear R=b1f54cd847a55fee
scenes/cornell.toml strategy-variance-linear samples.Y=615d8f2dd6e46958
scenes/cornell.toml strategy-variance-linear samples.density=1ac76540eb190da5
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
scenes/spheres_table.toml gradients grad.cdv.Y=c5fae2282e88bf34
scenes/spheres_table.toml gradients grad.cv.Y=8f96419e5fae73b4
scenes/spheres_table.toml gradients grad.dv.Y=2ec93f14c943dda6
scenes/spheres_table.toml gradients grad.indirect.Y=d1f00b96105f7e15
scenes/spheres_table.toml gradients grad.ratio.Y=f30e845571445150
scenes/spheres_table.toml gradients grad.sv.Y=9260f441b753c80f
scenes/spheres_table.toml gradients grad.u.B=7aebaff7926862e7
scenes/spheres_table.toml gradients grad.u.G=0a08e2667daf16a3
scenes/spheres_table.toml gradients grad.u.R=3b6b3bf36ee42263
scenes/spheres_table.toml gradients grad.v.B=70e019286ea84b99
scenes/spheres_table.toml gradients grad.v.G=5fd41dda82fd966d
scenes/spheres_table.toml gradients grad.v.R=3e7fff6f1e8543ea
scenes/spheres_table.toml gradients grad.vis.Y=8c7a85dc52e27f04
scenes/spheres_table.toml gradients normal.X=36b2c8c01db5115b
scenes/spheres_table.toml gradients normal.Y=3bd6e75721f15fd7
scenes/spheres_table.toml gradients normal.Z=2fbf8d3c2e020bc0
scenes/spheres_table.toml gradients object.id=b25d66d3a2238c85
scenes/spheres_table.toml gradients variance.B=94eb01d1af41fa81
scenes/spheres_table.toml gradients variance.G=96d7d798f8349439
scenes/spheres_table.toml gradients variance.R=34d02d6cac6aa722
scenes/spheres_table.toml strategy-gradient B=b86af24f1b5f7f1b
scenes/spheres_table.toml strategy-gradient G=18bafe42fc672e64
scenes/spheres_table.toml strategy-gradient R=4260129f5d366699
scenes/spheres_table.toml strategy-gradient samples.Y=6c445dd09d9fea08
scenes/spheres_table.toml strategy-gradient samples.density=b4a6707d36fafb65
scenes/spheres_table.toml strategy-variance-linear B=f32372eee6c5eb65
scenes/spheres_table.toml strategy-variance-linear G=276a30cfe10558f5
scenes/spheres_table.toml strategy-variance-linear R=d9d1762530ab4685
scenes/spheres_table.toml strategy-variance-linear samples.Y=8c4d5092786dacc8
scenes/spheres_table.toml strategy-variance-linear samples.density=498f8207d270c1e5
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
scenes/spheres_table_far.toml gradients grad.cdv.Y=b77be1c22badcd89
scenes/spheres_table_far.toml gradients grad.cv.Y=8f96419e5fae73b4
scenes/spheres_table_far.toml gradients grad.dv.Y=99857662967235fc
scenes/spheres_table_far.toml gradients grad.indirect.Y=c9ad5734742d4d2c
scenes/spheres_table_far.toml gradients grad.ratio.Y=345d3441fb8d0d08
scenes/spheres_table_far.toml gradients grad.sv.Y=267287e44674909b
scenes/spheres_table_far.toml gradients grad.u.B=06d9fb3991b3e82b
scenes/spheres_table_far.toml gradients grad.u.G=958884cf7b5c1789
scenes/spheres_table_far.toml gradients grad.u.R=5575b6cc28482076
scenes/spheres_table_far.toml gradients grad.v.B=9b1a0fea6f893015
scenes/spheres_table_far.toml gradients grad.v.G=84f5a5e1611158c7
scenes/spheres_table_far.toml gradients grad.v.R=c81b42eabfd555d3
scenes/spheres_table_far.toml gradients grad.vis.Y=d5456dae25a03bdb
scenes/spheres_table_far.toml gradients normal.X=36b2c8c01db5115b
scenes/spheres_table_far.toml gradients normal.Y=3bd6e75721f15fd7
scenes/spheres_table_far.toml gradients normal.Z=2fbf8d3c2e020bc0
scenes/spheres_table_far.toml gradients object.id=b25d66d3a2238c85
scenes/spheres_table_far.toml gradients variance.B=9286a0d6ef2cfa4a
scenes/spheres_table_far.toml gradients variance.G=7711ce682a500ae4
scenes/spheres_table_far.toml gradients variance.R=01b1b3d5f3726ca2
scenes/spheres_table_far.toml strategy-gradient B=70cd4de9eb1ce7f5
scenes/spheres_table_far.toml strategy-gradient G=fe60437074db87b6
scenes/spheres_table_far.toml strategy-gradient R=015ca43b573b2577
scenes/spheres_table_far.toml strategy-gradient samples.Y=6a7c96ae5a4ec7b8
scenes/spheres_table_far.toml strategy-gradient samples.density=6d1f8dc61b2f87c5
scenes/spheres_table_far.toml strategy-variance-linear B=9d510988deb1d7bc
scenes/spheres_table_far.toml strategy-variance-linear G=eb72c9ffb25d4432
scenes/spheres_table_far.toml strategy-variance-linear R=a9c99257fc2ac3fb
scenes/spheres_table_far.toml strategy-variance-linear samples.Y=86fd1b43ea790aa5
scenes/spheres_table_far.toml strategy-variance-linear samples.density=86fd1b43ea790aa5
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
scenes/three_spheres_env.toml strategy-gradient B=9a67a7a359c781c5
scenes/three_spheres_env.toml strategy-gradient G=5dd22457d5f98ee0
scenes/three_spheres_env.toml strategy-gradient R=346aefa6bad5f3d6
scenes/three_spheres_env.toml strategy-gradient samples.Y=5cd82ec04c76eaa8
scenes/three_spheres_env.toml strategy-gradient samples.density=fd4dba4517e08ea5
scenes/three_spheres_env.toml strategy-variance-linear B=2065112555543c9b
scenes/three_spheres_env.toml strategy-variance-linear G=41101aa6c46773fe
scenes/three_spheres_env.toml strategy-variance-linear R=2783332fb321e945
scenes/three_spheres_env.toml strategy-variance-linear samples.Y=0349d571013f5fe5
scenes/three_spheres_env.toml strategy-variance-linear samples.density=0349d571013f5fe5
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
scenes/objects_bumpy.toml gradients grad.cdv.Y=ebe48800c69baab9
scenes/objects_bumpy.toml gradients grad.cv.Y=4ab703ac8f64bc8d
scenes/objects_bumpy.toml gradients grad.dv.Y=a257e3308aa38386
scenes/objects_bumpy.toml gradients grad.indirect.Y=853d95fd2ca0554c
scenes/objects_bumpy.toml gradients grad.ratio.Y=afae60958e7ab5d4
scenes/objects_bumpy.toml gradients grad.sv.Y=04315cd99768e5c5
scenes/objects_bumpy.toml gradients grad.u.B=c223d9a038ffc907
scenes/objects_bumpy.toml gradients grad.u.G=2dc5743617b3d8f2
scenes/objects_bumpy.toml gradients grad.u.R=f37bbf5082888a7f
scenes/objects_bumpy.toml gradients grad.v.B=9321251cf93662ad
scenes/objects_bumpy.toml gradients grad.v.G=59ee19906b9147e5
scenes/objects_bumpy.toml gradients grad.v.R=beb1c8c8f9b4f231
scenes/objects_bumpy.toml gradients grad.vis.Y=ed4898a74f10c16e
scenes/objects_bumpy.toml gradients normal.X=09607217e1e59704
scenes/objects_bumpy.toml gradients normal.Y=8b378a27bc47df6c
scenes/objects_bumpy.toml gradients normal.Z=189f584810a7fa50
scenes/objects_bumpy.toml gradients object.id=6902b2516b8ed7b5
scenes/objects_bumpy.toml gradients variance.B=c5f5946794626659
scenes/objects_bumpy.toml gradients variance.G=cd069eb921c21654
scenes/objects_bumpy.toml gradients variance.R=33f4fc69bb6d4922
scenes/objects_bumpy.toml strategy-gradient B=8ca21d63dbf32f0f
scenes/objects_bumpy.toml strategy-gradient G=d45a963f80803c3a
scenes/objects_bumpy.toml strategy-gradient R=df5ef1c6ea8f40a3
scenes/objects_bumpy.toml strategy-gradient samples.Y=abf98ebe4c2af298
scenes/objects_bumpy.toml strategy-gradient samples.density=9cd338b9ad1bb785
scenes/objects_bumpy.toml strategy-variance-linear B=ada13dbf0d33875f
scenes/objects_bumpy.toml strategy-variance-linear G=1454e4502fcb1f1f
scenes/objects_bumpy.toml strategy-variance-linear R=9c1004b7c0a7d370
scenes/objects_bumpy.toml strategy-variance-linear samples.Y=b27e0463151223e8
scenes/objects_bumpy.toml strategy-variance-linear samples.density=69f925e602bdb085
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
scenes/bunny_env.toml gradients grad.cdv.Y=50ff4e2f6baf3211
scenes/bunny_env.toml gradients grad.cv.Y=e6385258253af167
scenes/bunny_env.toml gradients grad.dv.Y=cf924e9a89b1fa9b
scenes/bunny_env.toml gradients grad.indirect.Y=819d32af43fbf28d
scenes/bunny_env.toml gradients grad.ratio.Y=8237d9fadcd42690
scenes/bunny_env.toml gradients grad.sv.Y=4a0f8fe9556cc3b6
scenes/bunny_env.toml gradients grad.u.B=0a4bd6606c54321a
scenes/bunny_env.toml gradients grad.u.G=67ed19a4722c7205
scenes/bunny_env.toml gradients grad.u.R=29f76398a47b85f3
scenes/bunny_env.toml gradients grad.v.B=cdbe4d63b00e416f
scenes/bunny_env.toml gradients grad.v.G=a3cd7b6358a5aff9
scenes/bunny_env.toml gradients grad.v.R=56dae50098775ca2
scenes/bunny_env.toml gradients grad.vis.Y=1b16f0a56c9fa68f
scenes/bunny_env.toml gradients normal.X=649ea091c0d0fcb7
scenes/bunny_env.toml gradients normal.Y=79db0df63c6615de
scenes/bunny_env.toml gradients normal.Z=453f751b0e3fa4b9
scenes/bunny_env.toml gradients object.id=a487430f181d2238
scenes/bunny_env.toml gradients variance.B=94e1f2502a1489ba
scenes/bunny_env.toml gradients variance.G=8277646f3c9e5592
scenes/bunny_env.toml gradients variance.R=b5a249d64fcd8089
scenes/bunny_env.toml strategy-gradient B=3fd997a91b44ead3
scenes/bunny_env.toml strategy-gradient G=0d886e6deacef5e0
scenes/bunny_env.toml strategy-gradient R=aa89a03b04fc357c
scenes/bunny_env.toml strategy-gradient samples.Y=482e0a2b9615e585
scenes/bunny_env.toml strategy-gradient samples.density=9c83ce308a06b345
scenes/bunny_env.toml strategy-variance-linear B=4c2ce5c9d1ac6ac0
scenes/bunny_env.toml strategy-variance-linear G=a380badadba7f7c9
scenes/bunny_env.toml strategy-variance-linear R=8ad441a3d207b7dc
scenes/bunny_env.toml strategy-variance-linear samples.Y=f6fe318dff31eda8
scenes/bunny_env.toml strategy-variance-linear samples.density=05f3ab33f7d95fa5
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
scenes/validation/cornell.toml strategy-gradient B=1bc161c44e6ffd27
scenes/validation/cornell.toml strategy-gradient G=564ea43016bfeb92
scenes/validation/cornell.toml strategy-gradient R=713fdf08b8587de8
scenes/validation/cornell.toml strategy-gradient samples.Y=de320bd2ae8aac75
scenes/validation/cornell.toml strategy-gradient samples.density=142e6358632d82e5
scenes/validation/cornell.toml strategy-variance-linear B=65840035eb22eab3
scenes/validation/cornell.toml strategy-variance-linear G=79a01082b058897e
scenes/validation/cornell.toml strategy-variance-linear R=f881e74ae335bb72
scenes/validation/cornell.toml strategy-variance-linear samples.Y=7a9a262126edc958
scenes/validation/cornell.toml strategy-variance-linear samples.density=4c51dda5833a11a5
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
scenes/validation/env_constant.toml strategy-gradient B=0052eade660edaba
scenes/validation/env_constant.toml strategy-gradient G=935e3e4cd827c49f
scenes/validation/env_constant.toml strategy-gradient R=f53882fd0578d2e4
scenes/validation/env_constant.toml strategy-gradient samples.Y=f818a9aaa40e5d35
scenes/validation/env_constant.toml strategy-gradient samples.density=03232be2628e3985
scenes/validation/env_constant.toml strategy-variance-linear B=f06a41ee71403545
scenes/validation/env_constant.toml strategy-variance-linear G=c3928b035fb8767f
scenes/validation/env_constant.toml strategy-variance-linear R=c6d78715550e1316
scenes/validation/env_constant.toml strategy-variance-linear samples.Y=eaeba6918716f7b5
scenes/validation/env_constant.toml strategy-variance-linear samples.density=166db712f3466085
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
scenes/validation/env_image.toml strategy-gradient B=e3534e33b6dce1da
scenes/validation/env_image.toml strategy-gradient G=6eb55fff29622183
scenes/validation/env_image.toml strategy-gradient R=00b69ae8b2b10863
scenes/validation/env_image.toml strategy-gradient samples.Y=0f3bf61c155e4318
scenes/validation/env_image.toml strategy-gradient samples.density=521c3a2e067c7865
scenes/validation/env_image.toml strategy-variance-linear B=c8fc1e59ebc66db5
scenes/validation/env_image.toml strategy-variance-linear G=f69602c89912ff77
scenes/validation/env_image.toml strategy-variance-linear R=664e9497007444a4
scenes/validation/env_image.toml strategy-variance-linear samples.Y=279bc0e684dbb678
scenes/validation/env_image.toml strategy-variance-linear samples.density=030734ec25d9cbc5
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
scenes/validation/spheres.toml strategy-gradient B=794edb26cb7a7294
scenes/validation/spheres.toml strategy-gradient G=aae723f862a07d8e
scenes/validation/spheres.toml strategy-gradient R=6857e87fac678461
scenes/validation/spheres.toml strategy-gradient samples.Y=9b0c704a7c1501f8
scenes/validation/spheres.toml strategy-gradient samples.density=e91b8d7a0c4a5825
scenes/validation/spheres.toml strategy-variance-linear B=cc0246ebdf936c19
scenes/validation/spheres.toml strategy-variance-linear G=6466826ca561bcb2
scenes/validation/spheres.toml strategy-variance-linear R=c5c572781bf49622
scenes/validation/spheres.toml strategy-variance-linear samples.Y=07e2699ed9b14648
scenes/validation/spheres.toml strategy-variance-linear samples.density=87314d5bbb4afd25";
