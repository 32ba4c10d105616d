//! A results folder replaced whole: built beside the old one and exchanged with it in one step.
//!
//! [`write_swapped`] builds the new folder as a sibling, `.NAME` + [`SWAP`] + the process id,
//! holding the run's files, its manifest and a copy of the lock, then exchanges the two folders
//! by one rename (`renameat2` with `RENAME_EXCHANGE`, Linux): at every instant the folder's
//! path names one whole folder, the old or the new. The old one, left under the sibling's name,
//! is retired ([`retire`]): lamdyn's own dot-entries that the new folder lacks (a cache) move
//! into it, the files its manifest lists are removed, then the folder itself if nothing else is
//! in it. A run killed before or after the exchange leaves a sibling that the next run on the
//! folder retires ([`recover`]).
//!
//! Where the exchange is not available (another system, a file system without it, a mount
//! point), the sibling cannot be made (a parent folder that is not writable) or the process
//! stands in the folder (its current directory), [`Swap::Unsupported`] says so and the caller
//! writes file by file.

use super::{
    LOCK, MANIFEST, TEMPORARY, process_alive, read_manifest, remove_orphans, remove_stale,
};
use crate::error::{Context, Result};
use std::path::{Path, PathBuf};

/// What marks the folder being built (or retired) beside a results folder: `.NAME` + this +
/// the writing process's id.
pub(super) const SWAP: &str = ".lamdyn-swap-";

/// How a whole-folder write ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Swap {
    /// The new folder is in place and the old one retired.
    Done,
    /// Nothing was changed: the exchange is not available here.
    Unsupported,
}

/// Writes `files` and `manifest` as a new folder and swaps it in for `dir` (module docs).
///
/// # Errors
/// A file of the new folder cannot be written, or the exchange fails for another reason than
/// being unsupported; the folder is then as it was.
pub(super) fn write_swapped<S: AsRef<str>>(
    dir: &Path,
    files: &[(S, Vec<u8>)],
    manifest: &str,
) -> Result<Swap> {
    let dir = dir
        .canonicalize()
        .with_context(|| format!("cannot read the folder '{}'", dir.display()))?;
    // A folder this process stands in stays where it is (a shell there would be left in a
    // removed folder).
    let inside = std::env::current_dir().is_ok_and(|cwd| cwd.starts_with(&dir));
    let Some(staging) = sibling(&dir, std::process::id()).filter(|_| !inside) else {
        return Ok(Swap::Unsupported);
    };
    if std::fs::symlink_metadata(&staging).is_ok() {
        retire(&staging, &dir);
    }
    if std::fs::create_dir(&staging).is_err() {
        return Ok(Swap::Unsupported);
    }
    if let Err(e) = fill(&staging, &dir, files, manifest) {
        let _ = std::fs::remove_dir_all(&staging);
        return Err(e);
    }
    match exchange(&staging, &dir) {
        Ok(Swap::Done) => {
            retire(&staging, &dir);
            Ok(Swap::Done)
        }
        Ok(Swap::Unsupported) => {
            let _ = std::fs::remove_dir_all(&staging);
            Ok(Swap::Unsupported)
        }
        Err(e) => {
            let _ = std::fs::remove_dir_all(&staging);
            Err(e).with_context(|| format!("cannot replace the folder '{}'", dir.display()))
        }
    }
}

/// Retires the siblings of `dir` that runs no longer running left (killed before or after
/// their exchange), and this process's own from a write that failed.
pub(super) fn recover(dir: &Path) {
    let Ok(dir) = dir.canonicalize() else {
        return;
    };
    let (Some(parent), Some(name)) = (dir.parent(), dir.file_name()) else {
        return;
    };
    let prefix = format!(".{}{SWAP}", name.to_string_lossy());
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let entry_name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = entry_name
            .strip_prefix(&prefix)
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        let gone = pid == std::process::id() || !process_alive(pid);
        if gone && entry.file_type().is_ok_and(|t| t.is_dir()) {
            retire(&entry.path(), &dir);
        }
    }
}

/// `.NAME.lamdyn-swap-PID` beside the folder `dir`.
fn sibling(dir: &Path, pid: u32) -> Option<PathBuf> {
    let name = dir.file_name()?;
    Some(dir.with_file_name(format!(".{}{SWAP}{pid}", name.to_string_lossy())))
}

/// The new folder's contents: the manifest, the files, the lock (this process), with the old
/// folder's permissions.
fn fill<S: AsRef<str>>(
    staging: &Path,
    dir: &Path,
    files: &[(S, Vec<u8>)],
    manifest: &str,
) -> Result<()> {
    let write = |path: &Path, bytes: &[u8]| {
        std::fs::write(path, bytes).with_context(|| format!("cannot write '{}'", path.display()))
    };
    // The manifest first: a run killed while filling leaves a sibling that says what is in it.
    write(&staging.join(MANIFEST), manifest.as_bytes())?;
    for (name, bytes) in files {
        let path = staging.join(name.as_ref());
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("cannot create '{}'", parent.display()))?;
        }
        write(&path, bytes)?;
    }
    write(
        &staging.join(LOCK),
        format!("{}\n", std::process::id()).as_bytes(),
    )?;
    let permissions = std::fs::metadata(dir)
        .with_context(|| format!("cannot read the folder '{}'", dir.display()))?
        .permissions();
    std::fs::set_permissions(staging, permissions)
        .with_context(|| format!("cannot set the permissions of '{}'", staging.display()))
}

/// Empties and removes a sibling folder (module docs): lamdyn's dot-entries move into `dir`
/// where it has none of that name (else they are removed), the files its manifest lists, its
/// manifest, lock and dead temporary files are removed, then the folder if it is empty. Anything
/// else (a file put there by hand) is left, and so is the folder.
fn retire(sibling: &Path, dir: &Path) {
    if let Ok(entries) = std::fs::read_dir(sibling) {
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            let own = name.starts_with(".lamdyn") && name != MANIFEST && name != LOCK;
            if !own || name.contains(TEMPORARY) {
                continue;
            }
            let target = dir.join(&name);
            if std::fs::symlink_metadata(&target).is_err() {
                let _ = std::fs::rename(entry.path(), &target);
            } else if entry.file_type().is_ok_and(|t| t.is_dir()) {
                let _ = std::fs::remove_dir_all(entry.path());
            } else {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
    for name in read_manifest(sibling).unwrap_or_default() {
        remove_stale(sibling, &name);
    }
    let _ = std::fs::remove_file(sibling.join(MANIFEST));
    let _ = std::fs::remove_file(sibling.join(LOCK));
    remove_orphans(sibling);
    let _ = std::fs::remove_dir(sibling);
}

/// Exchanges two paths in one step; [`Swap::Unsupported`] where the file system lacks the
/// exchange (or the two are on different file systems).
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<Swap> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    use rustix::io::Errno;
    match renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE) {
        Ok(()) => Ok(Swap::Done),
        Err(e)
            if [
                Errno::XDEV,
                Errno::INVAL,
                Errno::NOSYS,
                Errno::OPNOTSUPP,
                Errno::BUSY,
            ]
            .contains(&e) =>
        {
            Ok(Swap::Unsupported)
        }
        Err(e) => Err(e.into()),
    }
}

/// Exchanges two paths in one step: not available on this system.
#[cfg(not(target_os = "linux"))]
fn exchange(_a: &Path, _b: &Path) -> std::io::Result<Swap> {
    Ok(Swap::Unsupported)
}

#[cfg(test)]
mod tests {
    use super::super::{OutputDir, list_files};
    use super::*;
    use lamdyn_testkit::TempDir;
    use std::collections::BTreeSet;

    /// The siblings `.NAME.lamdyn-swap-*` beside `dir`.
    fn siblings(dir: &Path) -> Vec<String> {
        let name = dir.file_name().unwrap().to_string_lossy().to_string();
        std::fs::read_dir(dir.parent().unwrap())
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().to_string())
            .filter(|n| n.starts_with(&format!(".{name}{SWAP}")))
            .collect()
    }

    /// Generation `g` of a results folder: a report, a result, figures, and every third
    /// generation one figure more (removed again by the next); 64 KiB per file, so a write
    /// takes long enough to be interrupted.
    fn generation(g: u64) -> Vec<(String, Vec<u8>)> {
        let mut names = vec![
            "report.html",
            "result.json",
            "figures/a.svg",
            "figures/b.svg",
        ];
        if g % 3 == 0 {
            names.push("figures/c.svg");
        }
        names
            .into_iter()
            .map(|n| {
                let mut bytes = format!("generation {g}\n").into_bytes();
                bytes.resize(64 << 10, b'.');
                (n.to_string(), bytes)
            })
            .collect()
    }

    /// Writes generation `g` into `dir` as a run does.
    fn write_generation(dir: &Path, g: u64) {
        OutputDir::prepare(dir, &[], false)
            .unwrap()
            .write(&generation(g))
            .unwrap();
    }

    /// Checks that `dir` holds one whole generation: the files its manifest lists, all of one
    /// generation, and no other. Returns the generation.
    fn whole_generation(dir: &Path) -> u64 {
        let present: BTreeSet<String> = list_files(dir).unwrap().into_iter().collect();
        let listed = read_manifest(dir).unwrap();
        assert_eq!(present, listed, "files against the manifest in {dir:?}");
        let gens: BTreeSet<u64> = present
            .iter()
            .map(|n| {
                let text = std::fs::read(dir.join(n)).unwrap();
                let line = text.split(|&b| b == b'\n').next().unwrap();
                let line = std::str::from_utf8(line).unwrap();
                line.strip_prefix("generation ").unwrap().parse().unwrap()
            })
            .collect();
        assert_eq!(gens.len(), 1, "a mixed folder: generations {gens:?}");
        let g = *gens.first().unwrap();
        assert_eq!(present, generation(g).into_iter().map(|(n, _)| n).collect());
        g
    }

    /// A rewrite replaces the folder whole: a cache in it moves into the new folder, the
    /// folder's permissions stay, and no sibling is left.
    #[test]
    fn the_folder_is_swapped_whole_and_keeps_its_cache() {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        let s = TempDir::new("swap");
        let dir = s.join("out");
        write_generation(&dir, 0);
        std::fs::create_dir_all(dir.join(".lamdyn-cache")).unwrap();
        std::fs::write(dir.join(".lamdyn-cache/entry"), "cached").unwrap();
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o750)).unwrap();
        let before = std::fs::metadata(&dir).unwrap().ino();
        write_generation(&dir, 1);
        assert_ne!(
            std::fs::metadata(&dir).unwrap().ino(),
            before,
            "not swapped"
        );
        assert_eq!(whole_generation(&dir), 1);
        assert_eq!(
            std::fs::read_to_string(dir.join(".lamdyn-cache/entry")).unwrap(),
            "cached"
        );
        let mode = std::fs::metadata(&dir).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o750);
        assert!(siblings(&dir).is_empty(), "{:?}", siblings(&dir));
        assert!(!dir.join(super::super::LOCK).exists());
    }

    /// Where the folder cannot be swapped, it is written file by file, and a file put by hand
    /// into a killed run's sibling is kept.
    #[test]
    fn a_sibling_with_a_stranger_s_file_is_kept() {
        let s = TempDir::new("stranger");
        let dir = s.join("out");
        write_generation(&dir, 0);
        // A killed run's sibling (this pid cannot exist: pid_max is at most 2^22) with the
        // run's files, its manifest, and a file someone put there.
        let sibling = s.join(format!(".out{SWAP}4194305"));
        std::fs::create_dir_all(&sibling).unwrap();
        std::fs::write(sibling.join("report.html"), "half").unwrap();
        std::fs::write(sibling.join(MANIFEST), "# header\nreport.html\n").unwrap();
        std::fs::write(sibling.join("notes.txt"), "mine").unwrap();
        write_generation(&dir, 1);
        assert_eq!(whole_generation(&dir), 1);
        assert!(!sibling.join("report.html").exists());
        assert_eq!(
            std::fs::read_to_string(sibling.join("notes.txt")).unwrap(),
            "mine"
        );
    }

    /// The folder `LAMDYN_SWAP_CHILD` names, rewritten generation after generation until the
    /// process is killed: the writer of [`a_kill_at_any_moment_leaves_a_whole_folder`]
    /// (ignored: does nothing without the variable).
    #[test]
    #[ignore = "the writer process of a_kill_at_any_moment_leaves_a_whole_folder"]
    fn swap_writer_child() {
        let Some(dir) = std::env::var_os("LAMDYN_SWAP_CHILD") else {
            return;
        };
        let dir = PathBuf::from(dir);
        let first: u64 = std::env::var("LAMDYN_SWAP_FIRST").unwrap().parse().unwrap();
        for g in first.. {
            write_generation(&dir, g);
        }
    }

    /// A writer killed (SIGKILL) at 20 random moments (fixed seed) leaves, each time, one whole
    /// generation in the folder, never a mix; the next run retires what it left, and the
    /// folder's cache survives every kill.
    #[test]
    fn a_kill_at_any_moment_leaves_a_whole_folder() {
        let s = TempDir::new("kill");
        let dir = s.join("out");
        write_generation(&dir, 0);
        std::fs::create_dir_all(dir.join(".lamdyn-cache")).unwrap();
        std::fs::write(dir.join(".lamdyn-cache/entry"), "cached").unwrap();
        let exe = std::env::current_exe().unwrap();
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = 1;
        let mut seen = BTreeSet::new();
        for _ in 0..20 {
            // xorshift64: delays of 5-80 ms after the writer starts.
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let delay = std::time::Duration::from_millis(5 + state % 76);
            let mut child = std::process::Command::new(&exe)
                .args(["--exact", "output::swap::tests::swap_writer_child"])
                .args(["--ignored", "--quiet", "--test-threads=1"])
                .env("LAMDYN_SWAP_CHILD", &dir)
                .env("LAMDYN_SWAP_FIRST", next.to_string())
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .spawn()
                .unwrap();
            std::thread::sleep(delay);
            child.kill().unwrap();
            child.wait().unwrap();
            let g = whole_generation(&dir);
            seen.insert(g);
            next = g.max(next) + 1000;
        }
        write_generation(&dir, next);
        assert_eq!(whole_generation(&dir), next);
        assert!(siblings(&dir).is_empty(), "{:?}", siblings(&dir));
        assert_eq!(
            std::fs::read_to_string(dir.join(".lamdyn-cache/entry")).unwrap(),
            "cached"
        );
        // The kills fell inside the writes, not all before the first one.
        assert!(seen.len() > 5, "generations seen: {seen:?}");
    }
}
