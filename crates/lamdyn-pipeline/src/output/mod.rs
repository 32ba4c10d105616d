//! Writing results without destroying anything lamdyn did not write.
//!
//! **Folders** ([`OutputDir`]). A results folder holds a manifest, `.lamdyn-manifest`, listing
//! the files lamdyn wrote there last time. A new run
//! 1. is checked before any work ([`OutputDir::prepare`]): the folder (or its nearest existing
//!    parent) must be writable; it must not hold the run's own inputs (the job file, the
//!    measurement) nor files lamdyn did not write ("foreign" files: anything not in the
//!    manifest, except lamdyn's own dot-entries such as `.lamdyn-cache`), unless `--force`;
//! 2. builds the new folder whole beside the old one and exchanges the two in one step
//!    (`output/swap.rs`): a failed or killed run leaves the earlier results as they were, a kill at any
//!    moment leaves the old or the new folder, never a mix, and the next run removes what a
//!    killed one left. lamdyn's dot-entries (a cache) move into the new folder; the previous
//!    run's files that this run did not write (a figure no longer produced) go with the old.
//! 3. where the folder cannot be swapped (`--force`, a file system without the exchange, a
//!    parent folder that is not writable, the current directory): writes each file to a
//!    temporary name beside its target, renames them into place when every file is written,
//!    then removes the files of the previous manifest that this run did not write again,
//!    never an input and never anything else, and writes the new manifest.
//!
//! From `prepare` to the end of the run the folder holds a lock ([`LOCK`]): a second run on
//! the same folder is refused at once, naming the process that holds it (a lock whose process
//! is gone is taken over), and the temporary files a killed run left are removed by the next
//! run's write.
//!
//! With `--force`, foreign files are kept and lamdyn writes beside them, never over them (a
//! foreign file with the name of one of lamdyn's outputs is refused, named), and no earlier
//! file is removed. An input is never written over, with or without `--force`. Inside the
//! folder no write follows a symbolic link (a linked file or subfolder is refused, named), and a
//! dangling link given as the folder is refused before any work.
//!
//! **Files** ([`write_file`]: a single file named by the user, such as `--json FILE`): a
//! temporary file renamed over the target. A symlink is written through (its target is
//! replaced, the link stays); a target that is not a regular file (a device, a FIFO, a folder)
//! is refused, as is an input of the run. [`write_own_file`] adds the folders' rule for a
//! format that marks its files as lamdyn's (a universal file's 151 header): an existing file
//! is replaced only when it carries that mark.

use crate::error::{Context, Result};
use crate::{bail, err};
use std::collections::BTreeSet;
use std::path::{Component, Path, PathBuf};

mod swap;

/// Name of the manifest in a results folder.
pub const MANIFEST: &str = ".lamdyn-manifest";

/// First line of a manifest.
const MANIFEST_HEADER: &str = "# lamdyn results: files written by lamdyn (one path per line, \
                               relative to this folder); lamdyn replaces or removes only these";

/// How many foreign names an error lists.
const LISTED: usize = 5;

/// How the caller spells the options a refusal points to: the CLI's flags, or the keyword
/// arguments of the Python module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OptionNames {
    /// The results folder's option.
    pub out: &'static str,
    /// The option that lets lamdyn write beside foreign files.
    pub force: &'static str,
}

impl OptionNames {
    /// `lamdyn`'s flags: `--out`, `--force`.
    pub const CLI: Self = Self {
        out: "--out",
        force: "--force",
    };
    /// Python's keyword arguments: `out`, `force=True`.
    pub const PYTHON: Self = Self {
        out: "out",
        force: "force=True",
    };
}

/// A results folder, checked and ready to receive files (module docs).
#[derive(Debug, Clone)]
pub struct OutputDir {
    dir: PathBuf,
    force: bool,
    names: OptionNames,
    inputs: Vec<PathBuf>,
    previous: BTreeSet<String>,
    /// Held from `prepare` until the last clone is dropped.
    _lock: std::sync::Arc<FolderLock>,
}

/// Name of the lock file in a results folder while a run may write there.
pub const LOCK: &str = ".lamdyn-lock";

/// A results folder's lock ([`LOCK`], holding the process id), released on drop; the folders
/// the lock created are removed again if nothing was written into them.
#[derive(Debug)]
struct FolderLock {
    path: PathBuf,
    /// The folders created for it, innermost first.
    created: Vec<PathBuf>,
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
        for dir in &self.created {
            // Only an empty folder is removed; a folder written into stops the walk.
            if std::fs::remove_dir(dir).is_err() {
                break;
            }
        }
    }
}

/// Whether process `pid` is running (Linux: its `/proc` entry, in a state other than zombie or
/// dead: a run killed before its parent reaped it keeps the entry but writes nothing more).
fn process_alive(pid: u32) -> bool {
    let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
        return Path::new(&format!("/proc/{pid}")).exists();
    };
    // "pid (comm) state ...": the command name may hold spaces and parentheses.
    let state = stat
        .rfind(')')
        .and_then(|i| stat[i + 1..].trim_start().chars().next());
    !matches!(state, Some('Z' | 'X' | 'x'))
}

impl FolderLock {
    /// Takes `dir`'s lock, creating the folder if needed; a lock left by a process that is no
    /// longer running is taken over. `names` spell the refusal's advice.
    ///
    /// # Errors
    /// Another run (its process named) holds the lock, or the folder or its lock cannot be
    /// created.
    fn acquire(dir: &Path, names: OptionNames) -> Result<Self> {
        use std::io::Write;
        let created: Vec<PathBuf> = dir
            .ancestors()
            .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
            .map(Path::to_path_buf)
            .collect();
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create '{}'", dir.display()))?;
        let path = dir.join(LOCK);
        let lock = |created: Vec<PathBuf>| Self {
            path: path.clone(),
            created,
        };
        for _ in 0..2 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut file) => {
                    let held = lock(created.clone());
                    writeln!(file, "{}", std::process::id())
                        .with_context(|| format!("cannot write '{}'", path.display()))?;
                    return Ok(held);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let holder = std::fs::read_to_string(&path)
                        .ok()
                        .and_then(|t| t.trim().parse::<u32>().ok());
                    if let Some(pid) = holder.filter(|&p| process_alive(p)) {
                        let who = if pid == std::process::id() {
                            "another run in this process".to_string()
                        } else {
                            format!("another lamdyn (process {pid})")
                        };
                        bail!(
                            "{who} is writing results into '{}': wait for it to finish, or choose \
                             another {} (if no such run is going, remove '{}')",
                            dir.display(),
                            names.out,
                            path.display()
                        );
                    }
                    // Left by a run that is gone (killed): taken over.
                    let _ = std::fs::remove_file(&path);
                }
                Err(e) => {
                    return Err(e).with_context(|| format!("cannot create '{}'", path.display()));
                }
            }
        }
        bail!(
            "cannot take the lock '{}': it came back as it was removed",
            path.display()
        )
    }
}

impl OutputDir {
    /// Checks `dir` before any work: writable, holding none of `inputs` and no foreign files
    /// (unless `force`), and takes its lock ([`LOCK`]; the folder is created for it and
    /// removed again if nothing was written) until the last clone is dropped.
    ///
    /// # Errors
    /// The folder is a file or a dangling link, cannot be created or written, another run
    /// holds it (its process named), holds an input (named), or holds files lamdyn did not
    /// write (the first few named) and `force` is off.
    pub fn prepare(dir: &Path, inputs: &[PathBuf], force: bool) -> Result<Self> {
        Self::prepare_named(dir, inputs, force, OptionNames::CLI)
    }

    /// [`OutputDir::prepare`] for a caller whose options are spelled `names` in its messages.
    ///
    /// # Errors
    /// As [`OutputDir::prepare`].
    pub fn prepare_named(
        dir: &Path,
        inputs: &[PathBuf],
        force: bool,
        names: OptionNames,
    ) -> Result<Self> {
        let inputs = canonical_paths(inputs);
        match std::fs::metadata(dir) {
            Ok(m) if !m.is_dir() => bail!(
                "{} '{}' is not a folder: give a folder for the results",
                names.out,
                dir.display()
            ),
            Ok(_) => probe_writable(dir)?,
            // Something is there that cannot be followed: a link to nothing.
            Err(_) if std::fs::symlink_metadata(dir).is_ok() => bail!(
                "{} '{}' is a symbolic link to nothing: give a folder for the results",
                names.out,
                dir.display()
            ),
            Err(_) => probe_writable(&nearest_existing(dir)?)?,
        }
        let lock = FolderLock::acquire(dir, names)?;
        swap::recover(dir);
        let out = Self {
            dir: dir.to_path_buf(),
            force,
            names,
            inputs,
            previous: read_manifest(dir)?,
            _lock: std::sync::Arc::new(lock),
        };
        out.check_contents()?;
        Ok(out)
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Refuses a folder holding inputs, or foreign files without `force`.
    fn check_contents(&self) -> Result<()> {
        let canonical = self
            .dir
            .canonicalize()
            .with_context(|| format!("cannot read the folder '{}'", self.dir.display()))?;
        if let Some(input) = self.inputs.iter().find(|p| p.starts_with(&canonical)) {
            let what = if *input == canonical { "is" } else { "holds" };
            if !self.force {
                bail!(
                    "the results folder '{}' {what} an input of this run ('{}'): lamdyn writes its \
                     results into a folder of their own; choose another {} (or {} to write beside \
                     the inputs, which are never written over)",
                    self.dir.display(),
                    input.display(),
                    self.names.out,
                    self.names.force
                );
            }
        }
        if self.force {
            return Ok(());
        }
        let foreign: Vec<String> = list_files(&self.dir)?
            .into_iter()
            .filter(|f| !self.previous.contains(f))
            .collect();
        if !foreign.is_empty() {
            let shown: Vec<String> = foreign
                .iter()
                .take(LISTED)
                .map(|f| format!("'{f}'"))
                .collect();
            bail!(
                "the results folder '{}' holds {} file(s) lamdyn did not write ({}{}): lamdyn does \
                 not delete them; choose a new or empty folder, or pass {} to write beside them",
                self.dir.display(),
                foreign.len(),
                shown.join(", "),
                if foreign.len() > LISTED { ", ..." } else { "" },
                self.names.force
            );
        }
        Ok(())
    }

    /// Refuses to write `name` (relative, checked) where a file lamdyn did not write stands, or
    /// through a symbolic link: at `name` itself or at any of its subfolders. `--force` lets
    /// lamdyn write beside foreign files, never over them; a link in the folder would send the
    /// write outside it.
    fn check_owned(&self, name: &str) -> Result<()> {
        let mut path = self.dir.clone();
        let parts: Vec<&str> = name.split('/').collect();
        for (k, part) in parts.iter().enumerate() {
            path.push(part);
            let Ok(meta) = std::fs::symlink_metadata(&path) else {
                return Ok(());
            };
            let here = parts[..=k].join("/");
            if meta.file_type().is_symlink() {
                bail!(
                    "cannot write '{name}' in '{}': '{here}' there is a symbolic link, and lamdyn \
                     does not write through links in its results folder; remove the link or choose \
                     another {}",
                    self.dir.display(),
                    self.names.out
                );
            }
            if k + 1 == parts.len() && !self.previous.contains(name) {
                bail!(
                    "cannot write '{name}' in '{}': a file of that name is there that lamdyn did \
                     not write; {} lets lamdyn write beside such files, never over them: move it \
                     or choose another {}",
                    self.dir.display(),
                    self.names.force,
                    self.names.out
                );
            }
        }
        Ok(())
    }

    /// Writes `files` (paths relative to the folder, `/`-separated subfolders allowed) with a
    /// new manifest. Without `force` the folder is replaced whole (`output/swap.rs`: a kill at any
    /// moment leaves the old or the new folder); with `force`, or where that is not available,
    /// file by file: all to temporary names first, then renamed into place, and the previous
    /// run's files that are not written again are removed (not with `force`).
    ///
    /// # Errors
    /// A name that leaves the folder, a target that is not a regular file or is an input, or an
    /// I/O error; before the swap or the renames, nothing of the earlier results has changed.
    pub fn write<S: AsRef<str>>(&self, files: &[(S, Vec<u8>)]) -> Result<()> {
        std::fs::create_dir_all(&self.dir)
            .with_context(|| format!("cannot create '{}'", self.dir.display()))?;
        // Checked again: the folder may have changed since `prepare` (another process).
        self.check_contents()?;
        remove_orphans(&self.dir);
        // Every name and target checked before anything is written: a refusal leaves the
        // folder as it was (no subfolder made for a file that is then not written).
        let mut names = BTreeSet::new();
        let mut targets: Vec<PathBuf> = Vec::with_capacity(files.len());
        for (name, _) in files {
            let name = check_relative(name.as_ref())?;
            if !names.insert(name.clone()) {
                bail!("'{name}' is written twice");
            }
            // An input or a file that is not regular first (named as such), then a link or a
            // foreign file in lamdyn's folder.
            targets.push(resolve_target(&self.dir.join(&name), &self.inputs)?);
            self.check_owned(&name)?;
        }
        if !self.force
            && swap::write_swapped(&self.dir, files, &manifest_text(&names))? == swap::Swap::Done
        {
            return Ok(());
        }
        let mut staged: Vec<(PathBuf, PathBuf)> = Vec::with_capacity(files.len());
        let result = (|| -> Result<()> {
            for ((_, bytes), target) in files.iter().zip(targets) {
                if let Some(parent) = target.parent() {
                    std::fs::create_dir_all(parent)
                        .with_context(|| format!("cannot create '{}'", parent.display()))?;
                }
                let tmp = temporary_beside(&target)?;
                std::fs::write(&tmp, bytes)
                    .with_context(|| format!("cannot write '{}'", tmp.display()))?;
                staged.push((tmp, target));
            }
            Ok(())
        })();
        if let Err(e) = result {
            for (tmp, _) in &staged {
                let _ = std::fs::remove_file(tmp);
            }
            return Err(e);
        }
        for (tmp, target) in &staged {
            std::fs::rename(tmp, target)
                .with_context(|| format!("cannot write '{}'", target.display()))?;
        }
        // The previous run's files not written again: removed (a figure no longer produced),
        // except inputs; with --force none are removed, and they stay lamdyn's in the manifest.
        let mut listed = names.clone();
        for stale in self.previous.difference(&names) {
            let path = self.dir.join(stale);
            let is_input = path.canonicalize().is_ok_and(|c| self.inputs.contains(&c));
            if self.force || is_input {
                if std::fs::symlink_metadata(&path).is_ok() {
                    listed.insert(stale.clone());
                }
            } else {
                remove_stale(&self.dir, stale);
            }
        }
        let path = self.dir.join(MANIFEST);
        let tmp = temporary_beside(&path)?;
        std::fs::write(&tmp, manifest_text(&listed))
            .and_then(|()| std::fs::rename(&tmp, &path))
            .with_context(|| format!("cannot write '{}'", path.display()))
    }
}

/// A manifest listing `names`.
fn manifest_text(names: &BTreeSet<String>) -> String {
    let mut manifest = String::from(MANIFEST_HEADER);
    for n in names {
        manifest.push('\n');
        manifest.push_str(n);
    }
    manifest.push('\n');
    manifest
}

/// Writes one file atomically (module docs): through a symlink, never over a non-regular file
/// or one of `inputs`.
///
/// # Errors
/// The target is not a regular file, is an input, or cannot be written.
pub fn write_file(path: &Path, bytes: &[u8], inputs: &[PathBuf]) -> Result<()> {
    let target = resolve_target(path, &canonical_paths(inputs))?;
    write_resolved(path, &target, bytes)
}

/// Writes `bytes` to `target` (the resolved `path`) through a temporary file beside it.
fn write_resolved(path: &Path, target: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temporary_beside(target)?;
    let written = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, target));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written.with_context(|| format!("cannot write '{}'", path.display()))
}

/// How much of an existing file [`write_own_file`] reads to recognise lamdyn's mark, bytes.
const MARK_BYTES: u64 = 4096;

/// Writes one file as [`write_file`] does, but replaces an existing file only when `is_own`
/// recognises its first bytes (at most 4 KiB) as lamdyn's: the folders' rule that lamdyn never
/// replaces a file it did not write, for a single file. `mark` says what lamdyn's files carry,
/// for the refusal.
///
/// # Errors
/// As [`write_file`]; an existing file without lamdyn's mark (named, with the mark expected).
pub fn write_own_file(
    path: &Path,
    bytes: &[u8],
    inputs: &[PathBuf],
    is_own: impl Fn(&[u8]) -> bool,
    mark: &str,
) -> Result<()> {
    use std::io::Read;
    let target = resolve_target(path, &canonical_paths(inputs))?;
    if target.exists() {
        let mut head = Vec::new();
        std::fs::File::open(&target)
            .and_then(|f| f.take(MARK_BYTES).read_to_end(&mut head))
            .with_context(|| format!("cannot read '{}'", path.display()))?;
        if !is_own(&head) {
            bail!(
                "cannot write '{}': it exists and lamdyn did not write it (it does not open with \
                 {mark}); lamdyn replaces only files it wrote: remove it or choose another name",
                path.display()
            );
        }
    }
    write_resolved(path, &target, bytes)
}

/// The paths that exist, canonical (an input that does not exist cannot be written over).
fn canonical_paths(paths: &[PathBuf]) -> Vec<PathBuf> {
    paths.iter().filter_map(|p| p.canonicalize().ok()).collect()
}

/// Checks a file target before any work: its folder exists and is writable, it is not a
/// non-regular file nor one of `inputs`.
///
/// # Errors
/// As [`write_file`] would fail.
pub fn check_file_target(path: &Path, inputs: &[PathBuf]) -> Result<()> {
    let target = resolve_target(path, &canonical_paths(inputs))?;
    let folder = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !folder.is_dir() {
        bail!(
            "cannot write '{}': the folder '{}' does not exist",
            path.display(),
            folder.display()
        );
    }
    probe_writable(&folder)
}

/// The file a write to `path` must replace: `path`, or a symlink's final target. Refuses a
/// non-regular file, a dangling link and an input.
fn resolve_target(path: &Path, inputs: &[PathBuf]) -> Result<PathBuf> {
    let target = match std::fs::symlink_metadata(path) {
        Err(_) => return Ok(path.to_path_buf()),
        Ok(m) if m.file_type().is_symlink() => path.canonicalize().with_context(|| {
            format!(
                "cannot write '{}': it is a symbolic link to nothing",
                path.display()
            )
        })?,
        Ok(_) => path.to_path_buf(),
    };
    let meta =
        std::fs::metadata(&target).with_context(|| format!("cannot write '{}'", path.display()))?;
    if !meta.is_file() {
        bail!(
            "cannot write '{}': it exists and is not a regular file ({}); lamdyn writes only \
             regular files",
            path.display(),
            kind_of(&meta)
        );
    }
    if let Ok(c) = target.canonicalize() {
        if inputs.contains(&c) {
            bail!(
                "cannot write '{}': it is an input of this run; write the results elsewhere",
                path.display()
            );
        }
    }
    Ok(target)
}

fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a folder"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

/// What marks a temporary file: `.NAME` + this + the writing process's id.
const TEMPORARY: &str = ".lamdyn-tmp-";

/// `.NAME.lamdyn-tmp-PID` beside `target`.
fn temporary_beside(target: &Path) -> Result<PathBuf> {
    let name = target
        .file_name()
        .ok_or_else(|| err!("'{}' is not a file name", target.display()))?;
    Ok(target.with_file_name(format!(
        ".{}{TEMPORARY}{}",
        name.to_string_lossy(),
        std::process::id()
    )))
}

/// The id of the process that wrote the temporary file `name`, if it is one.
fn temporary_writer(name: &str) -> Option<u32> {
    name.rsplit_once(TEMPORARY)
        .and_then(|(_, pid)| pid.parse().ok())
}

/// A relative, `/`-separated name inside the folder (no `..`, not absolute, not one of
/// lamdyn's dot-entries).
fn check_relative(name: &str) -> Result<String> {
    let p = Path::new(name);
    let ok = !name.is_empty()
        && p.components().all(|c| matches!(c, Component::Normal(_)))
        && !name.starts_with(".lamdyn");
    if ok {
        Ok(name.to_string())
    } else {
        Err(err!(
            "'{name}' is not a file name inside the results folder"
        ))
    }
}

/// The manifest's names (empty if there is none).
fn read_manifest(dir: &Path) -> Result<BTreeSet<String>> {
    let path = dir.join(MANIFEST);
    match std::fs::read_to_string(&path) {
        Ok(text) => Ok(text
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .filter(|l| check_relative(l).is_ok())
            .map(String::from)
            .collect()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(BTreeSet::new()),
        Err(e) => Err(e).with_context(|| format!("cannot read '{}'", path.display())),
    }
}

/// Every file and link under `dir` as a `/`-separated relative name, lamdyn's dot-entries
/// (manifest, cache, temporary files) left out; an empty subfolder counts as itself.
fn list_files(dir: &Path) -> Result<Vec<String>> {
    let mut out = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), String::new())];
    while let Some((path, prefix)) = stack.pop() {
        let entries = std::fs::read_dir(&path)
            .with_context(|| format!("cannot read '{}'", path.display()))?;
        let mut empty = true;
        for entry in entries {
            let entry = entry.with_context(|| format!("cannot read '{}'", path.display()))?;
            empty = false;
            let name = entry.file_name().to_string_lossy().to_string();
            if name.starts_with(".lamdyn") || name.contains(TEMPORARY) {
                continue;
            }
            let rel = format!("{prefix}{name}");
            let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
            if is_dir {
                stack.push((entry.path(), format!("{rel}/")));
            } else {
                out.push(rel);
            }
        }
        if empty && !prefix.is_empty() {
            out.push(prefix.trim_end_matches('/').to_string());
        }
    }
    out.sort();
    Ok(out)
}

/// Removes the temporary files (`.NAME.lamdyn-tmp-PID`) under `dir` that a killed run left:
/// those whose process is no longer running.
fn remove_orphans(dir: &Path) {
    let mut stack = vec![dir.to_path_buf()];
    while let Some(path) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&path) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().to_string();
            let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
            if is_dir {
                stack.push(entry.path());
                continue;
            }
            if temporary_writer(&name).is_some_and(|p| !process_alive(p)) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

/// Removes a file of the previous run (a link itself, not its target) and its subfolders if
/// they are left empty.
fn remove_stale(dir: &Path, name: &str) {
    let path = dir.join(name);
    if std::fs::symlink_metadata(&path).is_ok_and(|m| !m.is_dir()) {
        let _ = std::fs::remove_file(&path);
    }
    let mut parent = path.parent();
    while let Some(p) = parent {
        if p == dir || std::fs::remove_dir(p).is_err() {
            break;
        }
        parent = p.parent();
    }
}

/// The nearest existing ancestor of a folder that does not exist yet.
fn nearest_existing(dir: &Path) -> Result<PathBuf> {
    let mut p = dir.to_path_buf();
    loop {
        match p.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => p = parent.to_path_buf(),
            _ => return Ok(PathBuf::from(".")),
        }
        if let Ok(m) = std::fs::metadata(&p) {
            if m.is_dir() {
                return Ok(p);
            }
            bail!(
                "cannot create '{}': '{}' is not a folder",
                dir.display(),
                p.display()
            );
        }
    }
}

/// Creates and removes a probe file in `dir`: the only check that holds for every user
/// (root included) and every file system (read-only mounts included).
fn probe_writable(dir: &Path) -> Result<()> {
    let probe = dir.join(format!(".lamdyn-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| err!("cannot write into '{}': {e}", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    use lamdyn_testkit::TempDir;

    fn files(list: &[(&str, &str)]) -> Vec<(String, Vec<u8>)> {
        list.iter()
            .map(|(n, b)| (n.to_string(), b.as_bytes().to_vec()))
            .collect()
    }

    /// A re-run replaces lamdyn's files, removes the ones it no longer writes, and leaves no
    /// temporary file behind.
    #[test]
    fn rerun_replaces_own_files_and_removes_stale_ones() {
        let s = TempDir::new("rerun");
        let dir = s.join("out");
        let out = OutputDir::prepare(&dir, &[], false).unwrap();
        out.write(&files(&[("a.txt", "1"), ("figures/f.svg", "<svg/>")]))
            .unwrap();
        drop(out);
        let out = OutputDir::prepare(&dir, &[], false).unwrap();
        out.write(&files(&[("a.txt", "2")])).unwrap();
        assert_eq!(std::fs::read_to_string(dir.join("a.txt")).unwrap(), "2");
        assert!(!dir.join("figures").exists(), "stale figure folder left");
        let names = list_files(&dir).unwrap();
        assert_eq!(names, vec!["a.txt".to_string()]);
        drop(out);
        let all: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(
            all.len(),
            2,
            "a.txt and the manifest only, the lock released"
        );
    }

    /// A folder with a user's file is refused; with force the file is kept and lamdyn writes
    /// beside it.
    #[test]
    fn foreign_files_refuse_or_stay() {
        let s = TempDir::new("foreign");
        let dir = s.join("report");
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("sub/notes.docx"), "mine").unwrap();
        let e = OutputDir::prepare(&dir, &[], false)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("holds 1 file(s) lamdyn did not write ('sub/notes.docx')"),
            "{e}"
        );
        let out = OutputDir::prepare(&dir, &[], true).unwrap();
        out.write(&files(&[("a.txt", "1")])).unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.join("sub/notes.docx")).unwrap(),
            "mine"
        );
        // A later run without --force still refuses: notes.docx is not lamdyn's.
        drop(out);
        let e = OutputDir::prepare(&dir, &[], false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("did not write ('sub/notes.docx')"), "{e}");
    }

    /// The folder of the job's inputs is refused; even with force, an input is never written.
    #[test]
    fn inputs_are_never_written() {
        let s = TempDir::new("inputs");
        let job = s.join("job.toml");
        std::fs::write(&job, "x").unwrap();
        let e = OutputDir::prepare(s.path(), std::slice::from_ref(&job), false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("holds an input of this run"), "{e}");
        let out = OutputDir::prepare(s.path(), std::slice::from_ref(&job), true).unwrap();
        let e = out
            .write(&files(&[("job.toml", "y")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("is an input of this run"), "{e}");
        assert_eq!(std::fs::read_to_string(&job).unwrap(), "x");
        let e = write_file(&job, b"y", std::slice::from_ref(&job))
            .unwrap_err()
            .to_string();
        assert!(e.contains("is an input"), "{e}");
    }

    /// A symlink is written through; a FIFO is refused and stays a FIFO.
    #[test]
    fn symlinks_are_written_through_and_special_files_refused() {
        let s = TempDir::new("links");
        let real = s.join("real.json");
        std::fs::write(&real, "old").unwrap();
        let link = s.join("link.json");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_file(&link, b"new", &[]).unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read_to_string(&real).unwrap(), "new");
        let fifo = s.join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            let e = write_file(&fifo, b"x", &[]).unwrap_err().to_string();
            assert!(e.contains("not a regular file (a FIFO)"), "{e}");
            use std::os::unix::fs::FileTypeExt;
            assert!(
                std::fs::symlink_metadata(&fifo)
                    .unwrap()
                    .file_type()
                    .is_fifo()
            );
        }
        let e = write_file(s.path(), b"x", &[]).unwrap_err().to_string();
        assert!(e.contains("(a folder)"), "{e}");
    }

    /// With --force a user's file named like one of lamdyn's outputs is refused and kept; a
    /// linked file or subfolder in the folder is refused and its target untouched; a dangling
    /// link as the folder is refused before any work.
    #[test]
    fn force_writes_beside_never_over_and_links_are_not_followed() {
        let s = TempDir::new("force-links");
        let dir = s.join("report");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("report.html"), "mine").unwrap();
        let out = OutputDir::prepare(&dir, &[], true).unwrap();
        let e = out
            .write(&files(&[
                ("a.txt", "1"),
                ("figures/f.svg", "<svg/>"),
                ("report.html", "<html/>"),
            ]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("'report.html'") && e.contains("lamdyn did not write"),
            "{e}"
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("report.html")).unwrap(),
            "mine"
        );
        assert!(
            !dir.join("a.txt").exists() && !dir.join("figures").exists(),
            "nothing written or made before the refusal"
        );
        let outside = s.join("outside");
        std::fs::create_dir_all(&outside).unwrap();
        std::fs::write(outside.join("f.svg"), "theirs").unwrap();
        std::fs::remove_file(dir.join("report.html")).unwrap();
        std::os::unix::fs::symlink(&outside, dir.join("figures")).unwrap();
        drop(out);
        let out = OutputDir::prepare(&dir, &[], true).unwrap();
        let e = out
            .write(&files(&[("figures/f.svg", "<svg/>")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("'figures' there is a symbolic link"), "{e}");
        assert_eq!(
            std::fs::read_to_string(outside.join("f.svg")).unwrap(),
            "theirs"
        );
        std::os::unix::fs::symlink(outside.join("f.svg"), dir.join("table.csv")).unwrap();
        let e = out
            .write(&files(&[("table.csv", "x")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("'table.csv' there is a symbolic link"), "{e}");
        assert_eq!(
            std::fs::read_to_string(outside.join("f.svg")).unwrap(),
            "theirs"
        );
        let dangling = s.join("gone");
        std::os::unix::fs::symlink(s.join("nowhere"), &dangling).unwrap();
        let e = OutputDir::prepare(&dangling, &[], true)
            .unwrap_err()
            .to_string();
        assert!(e.contains("symbolic link to nothing"), "{e}");
    }

    /// A second run on a folder is refused while the first holds it, naming the process; the
    /// lock is released when the first is done, a lock of a process that is gone is taken
    /// over, a folder the lock created is removed if nothing was written, and a killed run's
    /// temporary files are removed by the next write.
    #[test]
    fn one_run_at_a_time_and_orphans_cleaned() {
        let s = TempDir::new("lock");
        let dir = s.join("out");
        let first = OutputDir::prepare(&dir, &[], false).unwrap();
        let e = OutputDir::prepare(&dir, &[], false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is writing results into"), "{e}");
        drop(first);
        assert!(!dir.exists(), "an empty folder the lock made is removed");
        std::fs::create_dir_all(&dir).unwrap();
        // pid_max is at most 2^22 on Linux: this process cannot exist.
        std::fs::write(dir.join(LOCK), "4194305\n").unwrap();
        std::fs::write(dir.join(".a.txt.lamdyn-tmp-4194305"), "half").unwrap();
        let out = OutputDir::prepare(&dir, &[], false).unwrap();
        out.write(&files(&[("a.txt", "1")])).unwrap();
        assert!(!dir.join(".a.txt.lamdyn-tmp-4194305").exists());
        drop(out);
        assert!(!dir.join(LOCK).exists());
        assert_eq!(std::fs::read_to_string(dir.join("a.txt")).unwrap(), "1");
    }

    /// A process that has exited but is not yet reaped (a zombie: a run killed whose parent has
    /// not waited for it) holds no lock; running, it does.
    #[test]
    #[cfg(target_os = "linux")]
    fn a_zombie_holds_no_lock() {
        let mut child = std::process::Command::new("sleep")
            .arg("0.2")
            .spawn()
            .unwrap();
        let pid = child.id();
        assert!(process_alive(pid));
        let stat = format!("/proc/{pid}/stat");
        let zombie = (0..500).any(|_| {
            std::thread::sleep(std::time::Duration::from_millis(10));
            std::fs::read_to_string(&stat).is_ok_and(|s| s.contains(") Z"))
        });
        assert!(zombie, "sleep did not exit within 5 s");
        assert!(!process_alive(pid));
        child.wait().unwrap();
        assert!(!process_alive(pid));
    }

    /// Names that leave the folder are refused; a file given as --out is refused.
    #[test]
    fn names_stay_inside_and_a_file_is_not_a_folder() {
        let s = TempDir::new("names");
        let out = OutputDir::prepare(&s.join("o"), &[], false).unwrap();
        for bad in ["../x", "/etc/x", "", ".lamdyn-manifest"] {
            assert!(out.write(&files(&[(bad, "1")])).is_err(), "{bad}");
        }
        let f = s.join("file");
        std::fs::write(&f, "").unwrap();
        assert!(OutputDir::prepare(&f, &[], false).is_err());
        assert!(OutputDir::prepare(&f.join("sub"), &[], false).is_err());
    }
}
