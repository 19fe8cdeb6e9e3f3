//! Atomic file replacement that leaves no temporary file behind, whatever stops
//! the process, and the EXR + PNG pair whose mismatch is always detectable.
//!
//! Why: a render can take minutes and may fail or be killed while an output is
//! being encoded. Writing in place would leave a truncated file *and* destroy the
//! previous good one; `rename(2)` within one directory is atomic, so a reader sees
//! the old file or the complete new one, never a mix. The temporary file lives in
//! the target's own directory because a rename across file systems is not atomic.
//!
//! # The scheme
//!
//! 1. [`stage`] writes into an **anonymous** file in the target's directory
//!    (Linux: `open(dir, O_TMPFILE)`). It has no name, so when the process dies —
//!    `SIGKILL`, `SIGTERM`, `SIGINT`, `SIGHUP`, a crash — the kernel frees it;
//!    nothing is left and no signal handler is needed. It is fsynced before
//!    [`stage`] returns.
//! 2. [`Staged::commit`] names it, `linkat("/proc/self/fd/N", ".NAME.gtmp-RANDOM")`,
//!    and renames that name over the target. Only between these two system
//!    calls does a temporary name exist.
//! 3. Every staged file holds an exclusive `flock` from the moment it exists
//!    until the process ends. [`stage`] first sweeps the directory: a
//!    `.*.gtmp-*` file whose lock it can take belongs to a dead process (locks
//!    die with their process; a reused PID inherits nothing) and is removed.
//!    (On a file system without `flock` the sweep cannot tell a live writer
//!    from a dead one and leaves such names alone.)
//! 5. No system call replaces a file by an anonymous one, so step 2's window
//!    cannot be closed, only made to leave nothing for long. Before the
//!    `linkat`, the writer records the temporary name in a **pending journal**
//!    (`$TMPDIR/gradtrace-pending-UID/`, one entry per name, itself created
//!    anonymous, locked and only then named, so an entry is never seen
//!    incomplete or unlocked while its writer lives) and removes the entry
//!    after the rename. [`sweep_pending`] — run at the start of every command
//!    and by every [`stage`] — removes the names recorded by entries whose lock
//!    it can take (their writer is dead), wherever they are. A kill inside the
//!    window (a 15 MB `merge` output, say) thus leaves its name until the next
//!    gradtrace command of that user, not until the next write to that one
//!    directory, which may never come. The journal is best effort: where it
//!    cannot be made, step 3 still applies.
//! 4. Names carry 64 random bits and are created exclusively (retried on the
//!    rare collision), so a leftover file, or a PID reused in a container, can
//!    never block a later write.
//!
//! Fallback (no `O_TMPFILE`: not Linux, a file system without it, or no
//! `/proc`): the temporary file is named (`.NAME.gtmp-RANDOM`) from the start,
//! locked at once, and swept as in step 3.
//!
//! # The EXR + PNG pair: mismatch detectable
//!
//! Two files cannot be renamed in one atomic step, so [`stage_pair`] makes a
//! mismatch *detectable*: both files carry the same render id (a hash of the
//! beauty pixels, the resolution and the exposure) — the EXR as the header
//! attribute [`RENDER_ID_KEY`], the PNG as a `tEXt` chunk of that keyword — and
//! [`StagedPair::commit`] renames the PNG first, the EXR last. A kill between the
//! two leaves the new PNG beside the old EXR, and [`check_pair`] reports their
//! ids as different; the EXR, the primary output, is always a complete file
//! from one render.
//!
//! # Output sets: the same, for many files
//!
//! A preview's images and `preview.json`, a report's assets, pages and kept
//! EXRs: [`StagedSet`] gives them one id and renames the JSON index (id and
//! file list) last; [`check_set`] reads the index and finds any listed file
//! of another run.

use super::OutputImage;
use crate::math::Vec3;
use crate::Error;
use std::ffi::{OsStr, OsString};
use std::fs::{File, OpenOptions};
use std::hash::{BuildHasher, Hasher};
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// What every temporary name contains: `.<target name>.gtmp-<16 hex digits>`.
const TEMP_MARK: &str = ".gtmp-";

/// The key of the render id: an EXR header attribute and a PNG `tEXt` keyword.
pub const RENDER_ID_KEY: &str = "gradtrace.render_id";

/// A fully written and fsynced file that has not yet replaced its target.
///
/// Dropping it without [`Staged::commit`] discards it (an anonymous file simply
/// vanishes; a named fallback file is removed), so every early return, and even
/// a panic, cleans up. Staging several files first and committing them
/// afterwards makes all fallible encoding happen before any visible output is
/// touched.
#[derive(Debug)]
pub struct Staged {
    /// Open and exclusively locked for the life of this value.
    file: File,
    target: PathBuf,
    /// The temporary name, once it has one (from the start in the fallback).
    temp: Option<PathBuf>,
    /// The pending-journal entry of an anonymous file's temporary name (step 5).
    journal: Option<Journaled>,
    committed: bool,
}

impl Staged {
    /// The path this file will have after [`Staged::commit`].
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Gives the file its temporary name (a no-op in the named fallback).
    fn name(&mut self) -> crate::Result<PathBuf> {
        if let Some(t) = &self.temp {
            return Ok(t.clone());
        }
        let temp = link_anonymous(&self.file, &self.target, &mut self.journal)
            .map_err(|e| output_error(&self.target, format!("cannot name the new file: {e}")))?;
        self.temp = Some(temp.clone());
        Ok(temp)
    }

    /// Renames the named file over the target.
    fn rename(&mut self) -> crate::Result<()> {
        let temp = self.name()?;
        std::fs::rename(&temp, &self.target)
            .map_err(|e| output_error(&self.target, format!("cannot replace the file: {e}")))?;
        self.committed = true;
        if let Some(j) = self.journal.take() {
            j.remove();
        }
        Ok(())
    }

    /// Puts the file in place of the target. On failure nothing is left of it
    /// and the previous target (if any) is untouched.
    pub fn commit(mut self) -> crate::Result<()> {
        self.rename()?;
        sync_dir(&self.target);
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let (false, Some(t)) = (self.committed, &self.temp) {
            let _ = std::fs::remove_file(t);
        }
        if let Some(j) = self.journal.take() {
            j.remove();
        }
    }
}

/// Makes the renames durable. Best effort: some file systems refuse to fsync a
/// directory, and the data is already safely in the files.
fn sync_dir(target: &Path) {
    if let Ok(dir) = File::open(parent_dir(target)) {
        let _ = dir.sync_all();
    }
}

/// Writes a file for `target` with `write`, flushes and fsyncs it, without
/// touching `target` (see the module doc). Any error discards the file.
pub fn stage<F>(target: &Path, write: F) -> crate::Result<Staged>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), String>,
{
    let file_name = target
        .file_name()
        .ok_or_else(|| output_error(target, "the path does not name a file".into()))?;
    // The last guard (commands check their outputs before any work): a rename
    // over a FIFO or a device would replace it with a regular file.
    super::input::check_output_target(target, "the output")?;
    let dir = parent_dir(target);
    sweep_pending();
    sweep_stale(dir);
    let (file, temp) = create_temp(dir, file_name)
        .map_err(|e| output_error(target, format!("cannot create a temporary file: {e}")))?;
    // From here on the guard owns the file and discards it on any exit.
    let staged = Staged {
        file,
        target: target.to_path_buf(),
        temp,
        journal: None,
        committed: false,
    };
    let handle = staged
        .file
        .try_clone()
        .map_err(|e| output_error(target, format!("cannot write: {e}")))?;
    let mut writer = BufWriter::new(handle);
    write(&mut writer).map_err(|m| output_error(target, m))?;
    let handle = writer
        .into_inner()
        .map_err(|e| output_error(target, format!("cannot write: {}", e.error())))?;
    handle
        .sync_all()
        .map_err(|e| output_error(target, format!("cannot sync to disk: {e}")))?;
    Ok(staged)
}

/// Replaces `target` atomically with what `write` produces (stage, then commit).
pub fn write_atomic<F>(target: &Path, write: F) -> crate::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), String>,
{
    stage(target, write)?.commit()
}

/// The directory a file lives in; `""` (a bare file name) means the current one.
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

pub(crate) fn output_error(path: &Path, message: String) -> Error {
    Error::Output {
        path: path.to_path_buf(),
        message,
    }
}

// ---------------------------------------------------------------------------
// Temporary files.
// ---------------------------------------------------------------------------

/// 64 bits that differ between processes (std's per-process random hash keys)
/// and between calls (a counter and the clock).
fn random_u64() -> u64 {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(COUNTER.fetch_add(1, Ordering::Relaxed));
    h.write_u32(std::process::id());
    if let Ok(t) = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH) {
        h.write_u128(t.as_nanos());
    }
    h.finish()
}

fn temp_path(dir: &Path, file_name: &OsStr) -> PathBuf {
    let mut name = OsString::from(".");
    name.push(file_name);
    name.push(format!("{TEMP_MARK}{:016x}", random_u64()));
    dir.join(name)
}

fn is_temp_name(name: &OsStr) -> bool {
    let name = name.to_string_lossy();
    name.starts_with('.')
        && name
            .rsplit_once(TEMP_MARK)
            .is_some_and(|(_, hex)| hex.len() == 16 && hex.bytes().all(|b| b.is_ascii_hexdigit()))
}

/// Test switch: forces the named fallback even where `O_TMPFILE` works.
static FORCE_NAMED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Forces the portable named-temp-file scheme (for tests of the fallback).
#[doc(hidden)]
pub fn force_named_temp_files(on: bool) {
    FORCE_NAMED.store(on, Ordering::SeqCst);
}

/// An exclusively locked new file: anonymous (`None`) where the system allows,
/// else named.
fn create_temp(dir: &Path, file_name: &OsStr) -> std::io::Result<(File, Option<PathBuf>)> {
    #[cfg(target_os = "linux")]
    if !FORCE_NAMED.load(Ordering::SeqCst) {
        if let Some(file) = linux::open_anonymous(dir) {
            // Brand new and nameless: nobody else can hold it. The lock only
            // matters for the moment it has a name; a file system without
            // flock just forgoes the sweep's protection of that moment.
            let _ = file.try_lock();
            return Ok((file, None));
        }
    }
    create_named(dir, file_name).map(|(f, p)| (f, Some(p)))
}

/// The fallback: a new file under a random name, locked, and checked to still be
/// the file at that name (a sweeper may have removed it between creation and
/// lock, when it looked abandoned).
fn create_named(dir: &Path, file_name: &OsStr) -> std::io::Result<(File, PathBuf)> {
    let mut last = None;
    for _ in 0..16 {
        let path = temp_path(dir, file_name);
        let file = match OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                last = Some(e);
                continue;
            }
            Err(e) => return Err(e),
        };
        // Locked by us (or locks unsupported: then no sweeper can take it
        // either), and still the file at that name.
        let locked = !matches!(file.try_lock(), Err(std::fs::TryLockError::WouldBlock));
        if locked && same_file(&file, &path) {
            return Ok((file, path));
        }
        last = Some(std::io::Error::other("the temporary file was taken over"));
    }
    Err(last.unwrap_or_else(|| std::io::Error::other("no free temporary name")))
}

#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_file: &File, path: &Path) -> bool {
    path.exists()
}

/// Names an anonymous file next to `target` (retrying on a name collision),
/// recording the name in the pending journal first (step 5; `journal` gets
/// the entry).
fn link_anonymous(
    file: &File,
    target: &Path,
    journal: &mut Option<Journaled>,
) -> std::io::Result<PathBuf> {
    let dir = parent_dir(target);
    let name = target.file_name().unwrap_or(OsStr::new("file"));
    #[cfg(target_os = "linux")]
    {
        let mut last = None;
        for _ in 0..16 {
            let path = temp_path(dir, name);
            if let Some(old) = journal.take() {
                old.remove();
            }
            *journal = Journaled::record(&path);
            match linux::link(file, &path) {
                Ok(()) => return Ok(path),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
                Err(e) => return Err(e),
            }
        }
        Err(last.unwrap_or_else(|| std::io::Error::other("no free temporary name")))
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (file, dir, name, journal);
        Err(std::io::Error::other("anonymous files need Linux"))
    }
}

// ---------------------------------------------------------------------------
// The pending journal (step 5 of the scheme).
// ---------------------------------------------------------------------------

/// This user's journal folder, created (mode 0700) when missing; `None` where
/// it cannot be made or is not this user's own folder.
#[cfg(target_os = "linux")]
fn journal_dir() -> Option<PathBuf> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt};
    // SAFETY: getuid has no preconditions and cannot fail.
    let uid = unsafe { libc::getuid() };
    let dir = std::env::temp_dir().join(format!("gradtrace-pending-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let m = std::fs::symlink_metadata(&dir).ok()?;
    (m.is_dir() && m.uid() == uid).then_some(dir)
}

#[cfg(not(target_os = "linux"))]
fn journal_dir() -> Option<PathBuf> {
    None
}

/// A journal entry: a locked file holding one temporary name. Dropped without
/// [`Journaled::remove`], it stays for [`sweep_pending`] (the process is dying).
#[derive(Debug)]
struct Journaled {
    path: PathBuf,
    _lock: File,
}

impl Journaled {
    /// Records `temp` (made absolute); `None` where the journal is unusable.
    #[cfg(target_os = "linux")]
    fn record(temp: &Path) -> Option<Self> {
        use std::io::Write;
        let dir = journal_dir()?;
        let abs = std::path::absolute(temp).ok()?;
        let mut file = linux::open_anonymous(&dir)?;
        file.try_lock().ok()?;
        file.write_all(abs.as_os_str().as_encoded_bytes()).ok()?;
        for _ in 0..16 {
            let path = dir.join(format!("{:016x}", random_u64()));
            match linux::link(&file, &path) {
                Ok(()) => return Some(Self { path, _lock: file }),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(_) => return None,
            }
        }
        None
    }

    #[cfg(not(target_os = "linux"))]
    fn record(_temp: &Path) -> Option<Self> {
        None
    }

    /// Removes the entry (its name is gone or in place: nothing to sweep).
    fn remove(self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Removes the temporary names that dead writers recorded in the pending
/// journal, and their entries (step 5). Best effort and cheap (the journal is
/// empty but for killed writers); every command calls it at its start.
pub fn sweep_pending() {
    let Some(dir) = journal_dir() else {
        return;
    };
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let Ok(file) = File::open(&path) else {
            continue;
        };
        // Locked: its writer lives (this process's own entries included:
        // flock conflicts between open files, not processes).
        if file.try_lock().is_err() || !same_file(&file, &path) {
            continue;
        }
        if let Ok(text) = std::fs::read(&path) {
            let temp = PathBuf::from(OsString::from(String::from_utf8_lossy(&text).as_ref()));
            // Only a temporary name, and only one whose own lock is free.
            if temp.file_name().is_some_and(is_temp_name) {
                if let Ok(t) = File::open(&temp) {
                    if t.try_lock().is_ok() && same_file(&t, &temp) {
                        let _ = std::fs::remove_file(&temp);
                    }
                }
            }
        }
        let _ = std::fs::remove_file(&path);
    }
}

/// The PID in a name of the scheme before this one, `.NAME.tmp-PID-N`.
fn legacy_pid(name: &OsStr) -> Option<u32> {
    let name = name.to_str()?;
    let (_, tail) = name.strip_prefix('.')?.rsplit_once(".tmp-")?;
    let (pid, n) = tail.split_once('-')?;
    n.parse::<u64>().ok()?;
    pid.parse().ok()
}

/// Whether a file of the old `.NAME.tmp-PID-N` scheme is certainly abandoned:
/// this process never makes such names, and a PID with no /proc entry is dead.
/// (A reused PID keeps it; harmless now that names never collide.)
fn legacy_is_stale(pid: u32) -> bool {
    pid == std::process::id()
        || (Path::new("/proc/self").is_dir() && !Path::new("/proc").join(pid.to_string()).exists())
}

/// Removes the temporary files of dead writers in `dir`: those whose lock can be
/// taken (and those of the old PID-named scheme whose writer is gone). Best
/// effort; never fails the write that triggered it.
fn sweep_stale(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        if legacy_pid(&entry.file_name()).is_some_and(legacy_is_stale) {
            let _ = std::fs::remove_file(entry.path());
            continue;
        }
        if !is_temp_name(&entry.file_name()) {
            continue;
        }
        let path = entry.path();
        let Ok(file) = File::open(&path) else {
            continue;
        };
        if file.try_lock().is_ok() && same_file(&file, &path) {
            let _ = std::fs::remove_file(&path);
        }
    }
}

#[cfg(target_os = "linux")]
mod linux {
    use std::fs::{File, OpenOptions};
    use std::os::unix::ffi::OsStrExt;
    use std::os::unix::fs::OpenOptionsExt;
    use std::os::unix::io::AsRawFd;
    use std::path::Path;

    /// `open(dir, O_TMPFILE | O_WRONLY, 0666)`; `None` where the file system (or
    /// a missing `/proc`, needed to name it later) does not allow it.
    pub(super) fn open_anonymous(dir: &Path) -> Option<File> {
        if !Path::new("/proc/self/fd").is_dir() {
            return None;
        }
        OpenOptions::new()
            .write(true)
            .custom_flags(libc::O_TMPFILE)
            .open(dir)
            .ok()
    }

    /// `linkat(AT_FDCWD, "/proc/self/fd/N", AT_FDCWD, path, AT_SYMLINK_FOLLOW)`:
    /// the documented way (open(2)) to give an `O_TMPFILE` file a name without
    /// `CAP_DAC_READ_SEARCH`.
    pub(super) fn link(file: &File, path: &Path) -> std::io::Result<()> {
        let from = std::ffi::CString::new(format!("/proc/self/fd/{}", file.as_raw_fd()))?;
        let to = std::ffi::CString::new(path.as_os_str().as_bytes())?;
        // SAFETY: both pointers are NUL-terminated strings that outlive the call;
        // linkat only reads them.
        let r = unsafe {
            libc::linkat(
                libc::AT_FDCWD,
                from.as_ptr(),
                libc::AT_FDCWD,
                to.as_ptr(),
                libc::AT_SYMLINK_FOLLOW,
            )
        };
        if r == 0 {
            Ok(())
        } else {
            Err(std::io::Error::last_os_error())
        }
    }
}

// ---------------------------------------------------------------------------
// The EXR + PNG pair.
// ---------------------------------------------------------------------------

/// The render id of a beauty image: the first 128 bits (hex) of SHA-256 over the
/// resolution, the exposure and the beauty's f32 bits. Deterministic, so that a
/// re-render of the same image writes byte-identical files.
pub fn render_id(beauty: &[Vec3], width: usize, height: usize, exposure: f32) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    h.update((width as u64).to_le_bytes());
    h.update((height as u64).to_le_bytes());
    h.update(exposure.to_bits().to_le_bytes());
    let mut buf = Vec::with_capacity(4096 * 12);
    for chunk in beauty.chunks(4096) {
        buf.clear();
        for p in chunk {
            for c in p.to_array() {
                buf.extend_from_slice(&c.to_bits().to_le_bytes());
            }
        }
        h.update(&buf);
    }
    crate::hex(&h.finalize()[..16])
}

/// An EXR and its PNG preview, staged under one render id.
#[derive(Debug)]
pub struct StagedPair {
    exr: Staged,
    png: Staged,
    id: String,
}

/// The steps of [`StagedPair::commit`], for tests that stop the process
/// between them.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairStep {
    /// The PNG is in place; the EXR is still anonymous.
    PngRenamed,
    /// The EXR has its temporary name (the only moment one exists).
    ExrNamed,
    /// Both are in place.
    ExrRenamed,
}

impl StagedPair {
    /// The id both files carry.
    pub fn render_id(&self) -> &str {
        &self.id
    }

    /// Renames the PNG, then the EXR, into place (see the module doc). An error
    /// before the first rename leaves both previous files untouched; one after
    /// it leaves the detectable mismatch a kill there would.
    pub fn commit(self) -> crate::Result<()> {
        self.commit_observed(&mut |_| {})
    }

    /// [`StagedPair::commit`], calling `step` after each step.
    #[doc(hidden)]
    pub fn commit_observed(mut self, step: &mut dyn FnMut(PairStep)) -> crate::Result<()> {
        self.png.rename()?;
        step(PairStep::PngRenamed);
        self.exr.name()?;
        step(PairStep::ExrNamed);
        self.exr.rename()?;
        sync_dir(&self.exr.target);
        if parent_dir(&self.png.target) != parent_dir(&self.exr.target) {
            sync_dir(&self.png.target);
        }
        step(PairStep::ExrRenamed);
        Ok(())
    }
}

/// Encodes `image` as the EXR at `exr` and its beauty `R,G,B` (tone-mapped at
/// `exposure`) as the PNG at `png`, both tagged with one render id, without
/// touching either path; [`StagedPair::commit`] puts them in place. This is how
/// a render's outputs should be written.
pub fn stage_pair(
    exr: &Path,
    image: &OutputImage,
    header: &super::ExrHeader,
    png: &Path,
    beauty: &[Vec3],
    exposure: f32,
) -> crate::Result<StagedPair> {
    let id = render_id(beauty, image.width, image.height, exposure);
    let exr = super::exr::stage_exr_tagged(exr, image, header, &id)?;
    let png =
        super::png::stage_png_tagged(png, beauty, image.width, image.height, exposure, Some(&id))?;
    Ok(StagedPair { exr, png, id })
}

/// [`stage_pair`] then [`StagedPair::commit`]; returns the render id.
pub fn write_pair(
    exr: &Path,
    image: &OutputImage,
    png: &Path,
    beauty: &[Vec3],
    exposure: f32,
) -> crate::Result<String> {
    let pair = stage_pair(
        exr,
        image,
        &super::ExrHeader::default(),
        png,
        beauty,
        exposure,
    )?;
    let id = pair.id.clone();
    pair.commit()?;
    Ok(id)
}

/// One EXR with a render id of its own (of `beauty`) and `header`'s
/// provenance: for files that belong to no set (cached references), so that
/// they too say where they came from. Returns the id.
pub fn write_exr_with_id(
    path: &Path,
    image: &OutputImage,
    header: &super::ExrHeader,
    beauty: &[Vec3],
) -> crate::Result<String> {
    let id = render_id(beauty, image.width, image.height, 0.0);
    super::exr::stage_exr_tagged(path, image, header, &id)?.commit()?;
    Ok(id)
}

/// What [`check_pair`] found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PairState {
    /// Both files carry this render id: they come from one render.
    Consistent(String),
    /// The ids differ, or one file has none (written by something else, or an
    /// older gradtrace): the two files must not be used together.
    Mismatched {
        exr: Option<String>,
        png: Option<String>,
    },
}

/// Compares the render ids of an EXR and its PNG (reading headers only).
pub fn check_pair(exr: &Path, png: &Path) -> crate::Result<PairState> {
    let e = super::exr::read_render_id(exr)?;
    let p = super::png::read_render_id(png)?;
    Ok(match (e, p) {
        (Some(a), Some(b)) if a == b => PairState::Consistent(a),
        (exr, png) => PairState::Mismatched { exr, png },
    })
}

// ---------------------------------------------------------------------------
// An output set: many files under one render id, the index last.
// ---------------------------------------------------------------------------

/// The id of an output set: the first 128 bits (hex) of SHA-256 over whatever
/// the caller feeds it (every image's pixels, the summary's text). Built from
/// the content, not drawn at random, so that a rerun that produces the same
/// set writes the same files, as [`render_id`] does for a pair.
pub struct SetIdHasher(sha2::Sha256);

impl Default for SetIdHasher {
    fn default() -> Self {
        Self::new()
    }
}

impl SetIdHasher {
    pub fn new() -> Self {
        use sha2::Digest;
        Self(sha2::Sha256::new_with_prefix(b"gradtrace output set v1\0"))
    }

    /// Adds a length-prefixed byte string (so that parts cannot run together).
    pub fn bytes(&mut self, b: &[u8]) -> &mut Self {
        use sha2::Digest;
        self.0.update((b.len() as u64).to_le_bytes());
        self.0.update(b);
        self
    }

    /// Adds the f32 bits of a plane.
    pub fn floats(&mut self, v: &[f32]) -> &mut Self {
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_bits().to_le_bytes()).collect();
        self.bytes(&bytes)
    }

    /// Adds the f32 bits of an RGB plane.
    pub fn rgb(&mut self, v: &[Vec3]) -> &mut Self {
        let bytes: Vec<u8> = v
            .iter()
            .flat_map(|p| p.to_array())
            .flat_map(|x| x.to_bits().to_le_bytes())
            .collect();
        self.bytes(&bytes)
    }

    /// Adds every channel of an image (names, size and data).
    pub fn image(&mut self, img: &OutputImage) -> &mut Self {
        self.bytes(&(img.width as u64).to_le_bytes());
        self.bytes(&(img.height as u64).to_le_bytes());
        for c in &img.channels {
            self.bytes(c.name.as_bytes());
            self.floats(&c.data);
        }
        self
    }

    pub fn finish(self) -> String {
        use sha2::Digest;
        crate::hex(&self.0.finalize()[..16])
    }
}

/// The JSON field of an index that names its set's id.
pub const SET_ID_FIELD: &str = "render_id";
/// The JSON field of an index that lists its set's files (relative to the index's folder).
pub const SET_FILES_FIELD: &str = "files";

/// Test hook: when this variable is set, [`StagedSet::commit`] exits the process
/// (status 86) after the members are in place and before the index is, as a
/// kill there would; `tests/output_sets.rs` checks that [`check_set`] sees it.
pub const STOP_BEFORE_INDEX_ENV: &str = "GRADTRACE_TEST_STOP_BEFORE_INDEX";

/// The files of one output set (a preview's images and `preview.json`, a
/// report's pages, assets and EXRs), all staged under one render id.
///
/// Many files cannot be renamed in one step, so, as for [`StagedPair`], a split
/// set is made *detectable*: every member carries the id (EXR header, PNG
/// `tEXt` chunk, a line of text, or a folder named by it), the members are
/// renamed first and the index — a JSON file naming the id and every member —
/// last. A reader who trusts the index can check each file it lists
/// ([`check_set`]); a kill before the index's rename leaves new members beside
/// the old index, whose id they do not carry.
#[derive(Debug)]
pub struct StagedSet {
    id: String,
    members: Vec<Staged>,
    index: Option<Staged>,
}

impl StagedSet {
    pub fn new(id: String) -> Self {
        Self {
            id,
            members: Vec::new(),
            index: None,
        }
    }

    /// The id every file of the set carries.
    pub fn render_id(&self) -> &str {
        &self.id
    }

    /// Stages an EXR with the id and `header`'s attributes (provenance).
    pub fn stage_exr(
        &mut self,
        path: &Path,
        image: &OutputImage,
        header: &super::ExrHeader,
    ) -> crate::Result<()> {
        let s = super::exr::stage_exr_tagged(path, image, header, &self.id)?;
        self.members.push(s);
        Ok(())
    }

    /// Stages a PNG of linear RGB (tone-mapped at `exposure`) with the id.
    pub fn stage_png(
        &mut self,
        path: &Path,
        rgb: &[Vec3],
        width: usize,
        height: usize,
        exposure: f32,
    ) -> crate::Result<()> {
        let s = super::png::stage_png_tagged(path, rgb, width, height, exposure, Some(&self.id))?;
        self.members.push(s);
        Ok(())
    }

    /// Stages a member whose bytes already show the id (a page with an id
    /// line) or that lies in a folder named by it (a report's assets).
    pub fn stage_bytes(&mut self, path: &Path, bytes: &[u8]) -> crate::Result<()> {
        let s = stage(path, |out| {
            use std::io::Write;
            out.write_all(bytes).map_err(|e| e.to_string())
        })?;
        self.members.push(s);
        Ok(())
    }

    /// Stages the index: `json` (an object) with [`SET_ID_FIELD`] and
    /// [`SET_FILES_FIELD`] (every member, relative to the index's folder) added.
    pub fn stage_index(&mut self, path: &Path, mut json: serde_json::Value) -> crate::Result<()> {
        let dir = parent_dir(path);
        let files: Vec<String> = self
            .members
            .iter()
            .map(|s| {
                let rel = s.target.strip_prefix(dir).unwrap_or(&s.target);
                rel.to_string_lossy().into_owned()
            })
            .collect();
        let map = json
            .as_object_mut()
            .ok_or_else(|| output_error(path, "the index must be a JSON object".into()))?;
        map.insert(SET_ID_FIELD.into(), self.id.clone().into());
        map.insert(SET_FILES_FIELD.into(), files.into());
        let text =
            serde_json::to_string_pretty(&json).map_err(|e| output_error(path, e.to_string()))?;
        self.index = Some(stage(path, |out| {
            use std::io::Write;
            out.write_all(text.as_bytes()).map_err(|e| e.to_string())
        })?);
        Ok(())
    }

    /// Renames the members, then the index, into place. An error before the
    /// first rename leaves every previous file untouched; one after it leaves a
    /// split set that [`check_set`] reports.
    pub fn commit(self) -> crate::Result<()> {
        let Self { members, index, .. } = self;
        let mut dirs: Vec<PathBuf> = Vec::new();
        for mut m in members {
            m.rename()?;
            let d = parent_dir(&m.target).to_path_buf();
            if !dirs.contains(&d) {
                dirs.push(d);
            }
        }
        for d in &dirs {
            if let Ok(dir) = File::open(d) {
                let _ = dir.sync_all();
            }
        }
        if std::env::var_os(STOP_BEFORE_INDEX_ENV).is_some() {
            std::process::exit(86);
        }
        match index {
            Some(i) => i.commit(),
            None => Ok(()),
        }
    }
}

/// What [`check_set`] found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SetState {
    /// Every listed file carries the index's id.
    Consistent(String),
    /// A listed file is missing or carries another id (or none).
    Mismatched {
        id: String,
        file: PathBuf,
        found: Option<String>,
    },
}

/// Checks the set an index (`preview.json`, `report.json`) describes: each file
/// it lists must carry its id: a file in a folder named by the id (a report's
/// assets) by that folder, else an EXR or PNG in its header, an HTML or
/// Markdown page as a `render_id: ` comment line.
pub fn check_set(index: &Path) -> crate::Result<SetState> {
    let bad = |m: String| crate::Error::Asset {
        path: index.to_path_buf(),
        message: m,
    };
    let text = std::fs::read_to_string(index).map_err(|source| crate::Error::Io {
        path: index.to_path_buf(),
        source,
    })?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| bad(format!("invalid JSON: {e}")))?;
    let id = json[SET_ID_FIELD]
        .as_str()
        .ok_or_else(|| bad(format!("expected a string field `{SET_ID_FIELD}`")))?
        .to_string();
    let files = json[SET_FILES_FIELD]
        .as_array()
        .ok_or_else(|| bad(format!("expected an array field `{SET_FILES_FIELD}`")))?;
    let dir = parent_dir(index);
    for f in files {
        let rel = f
            .as_str()
            .ok_or_else(|| bad(format!("`{SET_FILES_FIELD}` must hold strings")))?;
        let path = dir.join(rel);
        let found = member_id(&path, &id);
        if found.as_deref() != Some(id.as_str()) {
            return Ok(SetState::Mismatched {
                id,
                file: path,
                found,
            });
        }
    }
    Ok(SetState::Consistent(id))
}

/// The id a member carries (`None`: missing, unreadable or untagged).
fn member_id(path: &Path, id: &str) -> Option<String> {
    let folder = path.parent().and_then(Path::file_name);
    if folder.is_some_and(|f| f == OsStr::new(id)) {
        return path.is_file().then(|| id.to_string());
    }
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "exr" => super::exr::read_render_id(path).ok().flatten(),
        "png" => super::png::read_render_id(path).ok().flatten(),
        "json" | "md" | "html" => {
            let text = std::fs::read_to_string(path).ok()?;
            text.lines()
                .find_map(|l| l.split_once("render_id: ").map(|(_, r)| r))
                .map(|r| r.chars().take_while(char::is_ascii_hexdigit).collect())
        }
        // Neither tagged nor in the id's folder.
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_names_are_recognised_and_unique() {
        let a = temp_path(Path::new("d"), OsStr::new("out.exr"));
        let b = temp_path(Path::new("d"), OsStr::new("out.exr"));
        assert_ne!(a, b);
        assert!(is_temp_name(a.file_name().unwrap()));
        assert!(!is_temp_name(OsStr::new("out.exr")));
        assert!(!is_temp_name(OsStr::new(".out.exr.tmp-12-0")));
        assert!(!is_temp_name(OsStr::new(".out.gtmp-xyz")));
        assert_eq!(legacy_pid(OsStr::new(".out.exr.tmp-123-0")), Some(123));
        assert_eq!(legacy_pid(OsStr::new("out.exr")), None);
    }
}
