//! Output files under signals: child processes are killed (SIGKILL, SIGTERM,
//! SIGINT, SIGHUP) mid-write, between the PNG and EXR renames and inside the one
//! moment a temporary name exists; afterwards no temporary file may remain
//! (or it must be swept by the next write), previous outputs must be intact, and
//! an EXR/PNG mismatch must be detected by `check_pair`.
//!
//! The child is this test binary itself, re-run on the test `child_entry` with
//! `KILL_CHILD_MODE` set; it prints `@@<marker>` lines to say where it stopped.
#![cfg(target_os = "linux")]

use gradtrace::math::Vec3;
use gradtrace::output::atomic::{self, check_pair, PairState, PairStep};
use gradtrace::output::{self, OutputImage};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

const MODE: &str = "KILL_CHILD_MODE";
const DIR: &str = "KILL_CHILD_DIR";

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-kill-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn temp_files(dir: &Path) -> Vec<String> {
    entries(dir)
        .into_iter()
        .filter(|e| e.contains(".gtmp-") || e.contains(".tmp-"))
        .collect()
}

/// A 3×2 image of one value, with its beauty.
fn image(value: f32) -> (OutputImage, Vec<Vec3>) {
    let beauty = vec![Vec3::new(value, 0.5 * value, 0.25); 6];
    let mut img = OutputImage::new(3, 2);
    img.push_vec3("", output::names::RGB, &beauty);
    img.push_scalar("depth.Z", vec![value; 6]);
    (img, beauty)
}

fn write_version(dir: &Path, value: f32) -> String {
    let (img, beauty) = image(value);
    atomic::write_pair(
        &dir.join("out.exr"),
        &img,
        &dir.join("out.png"),
        &beauty,
        0.0,
    )
    .unwrap()
}

fn say(marker: &str) {
    println!("\n@@{marker}");
    std::io::stdout().flush().unwrap();
}

fn park() -> ! {
    loop {
        std::thread::sleep(Duration::from_secs(60));
    }
}

/// The child's side: does what `KILL_CHILD_MODE` says and stops at its marker.
#[test]
fn child_entry() {
    let (Ok(mode), Ok(dir)) = (std::env::var(MODE), std::env::var(DIR)) else {
        return; // not a child: nothing to do
    };
    let dir = PathBuf::from(dir);
    // A parent started under `nohup` (or a shell that ignores a signal) passes the
    // ignored disposition on; the child must die of every signal the tests send.
    for (signal, _) in SIGNALS {
        // SAFETY: restoring the default action of a standard signal in this process.
        unsafe { libc::signal(signal, libc::SIG_DFL) };
    }
    if mode.starts_with("fallback") {
        atomic::force_named_temp_files(true);
    }
    match mode.as_str() {
        "mid_write" | "fallback_mid_write" => {
            let _staged = atomic::stage(&dir.join("out.exr"), |w| {
                w.write_all(&vec![7u8; 1 << 20])
                    .map_err(|e| e.to_string())?;
                w.flush().map_err(|e| e.to_string())?;
                say("writing");
                park()
            });
        }
        "between_renames" | "exr_named" => {
            let (img, beauty) = image(2.0);
            let pair = atomic::stage_pair(
                &dir.join("out.exr"),
                &img,
                &Default::default(),
                &dir.join("out.png"),
                &beauty,
                0.0,
            )
            .unwrap();
            let stop = if mode == "exr_named" {
                PairStep::ExrNamed
            } else {
                PairStep::PngRenamed
            };
            pair.commit_observed(&mut |s| {
                if s == stop {
                    say("stopped");
                    park()
                }
            })
            .unwrap();
        }
        other => panic!("unknown child mode {other}"),
    }
}

/// Starts the child in `mode` and waits for its marker.
fn start_child(mode: &str, dir: &Path) -> Child {
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "child_entry",
            "--nocapture",
            "--test-threads",
            "1",
        ])
        .env(MODE, mode)
        .env(DIR, dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    for line in BufReader::new(stdout).lines() {
        if line.unwrap().contains("@@") {
            return child;
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    panic!("child in mode {mode} ended before its marker");
}

fn kill(child: &mut Child, signal: i32) {
    // SAFETY: sending a signal to our own child process, by its pid.
    let r = unsafe { libc::kill(child.id() as i32, signal) };
    assert_eq!(r, 0, "kill failed");
    let status = child.wait().unwrap();
    assert!(!status.success(), "the child was stopped by the signal");
}

const SIGNALS: [(i32, &str); 4] = [
    (libc::SIGKILL, "SIGKILL"),
    (libc::SIGTERM, "SIGTERM"),
    (libc::SIGINT, "SIGINT"),
    (libc::SIGHUP, "SIGHUP"),
];

#[test]
fn a_kill_mid_write_leaves_no_temporary_file_and_the_old_pair_intact() {
    for (signal, name) in SIGNALS {
        let dir = temp_dir(&format!("midwrite-{name}"));
        let v1 = write_version(&dir, 1.0);
        let mut child = start_child("mid_write", &dir);
        kill(&mut child, signal);
        assert_eq!(entries(&dir), ["out.exr", "out.png"], "{name}");
        assert_eq!(
            check_pair(&dir.join("out.exr"), &dir.join("out.png")).unwrap(),
            PairState::Consistent(v1.clone()),
            "{name}"
        );
        println!("{name} mid-write: no temporary file, previous pair {v1} intact");
    }
}

#[test]
fn a_kill_between_the_renames_is_detected_by_check_pair() {
    for (signal, name) in SIGNALS {
        let dir = temp_dir(&format!("between-{name}"));
        let v1 = write_version(&dir, 1.0);
        let mut child = start_child("between_renames", &dir);
        kill(&mut child, signal);
        // The EXR was still anonymous: nothing but the two outputs.
        assert_eq!(entries(&dir), ["out.exr", "out.png"], "{name}");
        match check_pair(&dir.join("out.exr"), &dir.join("out.png")).unwrap() {
            PairState::Mismatched {
                exr: Some(e),
                png: Some(p),
            } => {
                assert_eq!(e, v1, "the EXR is the previous, complete one");
                assert_ne!(p, v1, "the PNG is the new one");
            }
            other => panic!("{name}: expected a detected mismatch, got {other:?}"),
        }
        // The next write makes the pair consistent again.
        let v3 = write_version(&dir, 3.0);
        assert_eq!(
            check_pair(&dir.join("out.exr"), &dir.join("out.png")).unwrap(),
            PairState::Consistent(v3)
        );
        println!("{name} between renames: mismatch detected");
    }
}

#[test]
fn a_kill_while_a_temporary_name_exists_is_swept_by_the_next_write() {
    let dir = temp_dir("named");
    write_version(&dir, 1.0);
    let mut child = start_child("exr_named", &dir);
    kill(&mut child, libc::SIGKILL);
    let left = temp_files(&dir);
    // The one named moment (a write of a test beside this one may already
    // have swept it through the pending journal).
    assert!(left.len() <= 1, "the one named moment: {left:?}");
    // Its owner is dead, so its lock is free: the next write removes it.
    let v = write_version(&dir, 4.0);
    assert_eq!(temp_files(&dir), Vec::<String>::new());
    assert_eq!(
        check_pair(&dir.join("out.exr"), &dir.join("out.png")).unwrap(),
        PairState::Consistent(v)
    );
}

/// Issue 54: a kill inside the named moment (a 15 MB `merge` output, say) left
/// the name until the next write to that very folder, which may never come.
/// The pending journal lets the next gradtrace command, whatever it writes and
/// wherever, remove it.
#[test]
fn a_kill_while_a_temporary_name_exists_leaves_it_only_until_the_next_command() {
    let dir = temp_dir("named-elsewhere");
    write_version(&dir, 1.0);
    let mut child = start_child("exr_named", &dir);
    kill(&mut child, libc::SIGKILL);
    assert!(temp_files(&dir).len() <= 1);
    // A command that writes nothing, in another folder.
    let elsewhere = temp_dir("named-elsewhere-cwd");
    let o = Command::new(env!("CARGO_BIN_EXE_gradtrace"))
        .args(["diff", "missing-a.exr", "missing-b.exr"])
        .current_dir(&elsewhere)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        temp_files(&dir),
        Vec::<String>::new(),
        "swept by that command"
    );
    assert_eq!(entries(&dir), ["out.exr", "out.png"]);
    assert_eq!(entries(&elsewhere), Vec::<String>::new());
}

#[test]
fn named_fallback_files_of_dead_writers_are_swept_and_live_ones_kept() {
    for (signal, name) in SIGNALS {
        let dir = temp_dir(&format!("fallback-{name}"));
        write_version(&dir, 1.0);
        // A live writer's file is locked: a write beside it must keep it.
        let mut child = start_child("fallback_mid_write", &dir);
        assert_eq!(temp_files(&dir).len(), 1);
        write_version(&dir, 2.0);
        assert_eq!(
            temp_files(&dir).len(),
            1,
            "{name}: a live writer's file is kept"
        );
        kill(&mut child, signal);
        assert_eq!(
            temp_files(&dir).len(),
            1,
            "{name}: named, so it outlives its writer"
        );
        let v = write_version(&dir, 3.0);
        assert_eq!(temp_files(&dir), Vec::<String>::new(), "{name}: swept");
        assert_eq!(
            check_pair(&dir.join("out.exr"), &dir.join("out.png")).unwrap(),
            PairState::Consistent(v)
        );
    }
}

#[test]
fn leftovers_and_reused_pids_never_block_a_write() {
    let dir = temp_dir("reused-pid");
    let pid = std::process::id();
    // What the old scheme leaked, under this very PID, and a stale new-style name.
    for name in [
        format!(".out.exr.tmp-{pid}-0"),
        format!(".out.png.tmp-{pid}-0"),
        ".out.exr.gtmp-0000000000000000".to_string(),
    ] {
        std::fs::write(dir.join(&name), b"stale").unwrap();
    }
    for named in [false, true] {
        atomic::force_named_temp_files(named);
        for k in 0..3 {
            write_version(&dir, k as f32);
        }
    }
    atomic::force_named_temp_files(false);
    // This process never makes the old names, so those with its PID are stale.
    assert_eq!(temp_files(&dir), Vec::<String>::new(), "all swept");
    assert_eq!(entries(&dir), ["out.exr", "out.png"]);
}

/// The `gradtrace` binary killed at many moments of a render: no temporary
/// file may survive the next run, and whatever outputs exist are complete.
#[test]
fn the_binary_killed_at_any_moment_leaves_no_temporary_file() {
    let dir = temp_dir("binary");
    std::fs::write(
        dir.join("scene.toml"),
        "[camera]\nfrom = [0, 0, 5]\nto = [0, 0, 0]\nfov = 40\nresolution = [96, 64]\n\
         [render]\nspp = 16\n[materials.w]\ntype = \"lambert\"\nalbedo = [0.8, 0.8, 0.8]\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"w\"\n\
         [environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n",
    )
    .unwrap();
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_gradtrace"))
            .args([
                "render",
                "scene.toml",
                "--out",
                "out.exr",
                "-q",
                "--threads",
                "1",
            ])
            .current_dir(&dir)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap()
    };
    // How long a full run takes, to spread the kills over it.
    let t0 = std::time::Instant::now();
    assert!(run().wait().unwrap().success());
    let full = t0.elapsed();
    let mut leftovers = 0;
    for k in 0..24u32 {
        let (signal, _) = SIGNALS[k as usize % SIGNALS.len()];
        let mut child = run();
        std::thread::sleep(full.mul_f64(f64::from(k) / 20.0));
        // SAFETY: signalling our own child by its pid.
        unsafe { libc::kill(child.id() as i32, signal) };
        let _ = child.wait();
        leftovers += temp_files(&dir).len();
        for f in ["out.exr", "out.png"] {
            let p = dir.join(f);
            if p.exists() && f.ends_with(".exr") {
                output::read_exr(&p).expect("a complete EXR");
            }
        }
    }
    assert!(run().wait().unwrap().success());
    assert_eq!(temp_files(&dir), Vec::<String>::new());
    println!(
        "24 kills over a {full:?} run: {leftovers} temporary names seen between runs, none after"
    );
}
