//! Files in and out: the one atomic writer every gdsky command and the build-script API use, the
//! checks they run on their outputs before any work, and bounded reading.
//!
//! # Writing: [`write_atomically`]
//!
//! The bytes go into a fresh temporary file in the destination's directory (same file system,
//! so the rename cannot degrade into a copy), are flushed to disk, and the file is renamed over
//! the destination. A reader sees the old file or the complete new one, never a truncated one;
//! on any failure the temporary file is removed and the destination is untouched.
//!
//! What the destination may be:
//!
//! * **absent**, in an existing directory: it is created. Directories are not created here
//!   ([`check_output_dir`] / [`create_output_dir`] do that for commands whose contract says so).
//! * **a regular file**: it is replaced, keeping its permission bits.
//! * **a symbolic link**: the write goes *through* the link: the chain of links is followed to
//!   its end, which must be a regular file or absent (in an existing directory), and the
//!   temporary file and the rename happen in *that* file's directory. The link survives and
//!   points at the new content. The link is the user's (`latest.exr -> run42.exr`, a file kept
//!   under version control elsewhere, a path set up by a build system); replacing it with a
//!   regular file would silently cut that connection, and writing through it is what a shell
//!   redirection or an editor does. A chain longer than 40 links is refused (a loop).
//! * **anything else is refused**, with an error saying what it is: a directory, a FIFO, a
//!   character or block device (`/dev/full`), a socket. Renaming over them would destroy them
//!   (as root, `gdsky render -o /dev/full` used to replace the device with a regular file);
//!   writing into them would not be atomic. A path ending in `/` names a directory and is
//!   refused too.
//!
//! The destination is checked once when the write starts and again right before the rename, so a
//! special file that appears meanwhile is not replaced either; only a hostile process racing the
//! rename itself could slip one in.
//!
//! # Checking before work: [`check_output`], [`check_output_dir`]
//!
//! A command checks every place it will write *before* it renders or converts anything, so that a
//! typo in `-o` costs nothing: [`check_output`] applies the rules above and also proves the
//! directory writable by creating and removing a temporary file there (the only test that also
//! covers read-only file systems, ACLs and root); [`check_output_dir`] does the same for an
//! output folder, which may be missing when the command creates it and its nearest existing
//! ancestor is a writable directory.
//!
//! # Reading: [`read_limited`]
//!
//! Every input (shaders and their includes, EXR images, scene files, Godot resources, cache
//! files) is read with [`read_limited`]: regular files only, refused from their metadata before they are opened (a FIFO's
//! open blocks, `/dev/zero` never ends), and never more than a limit per kind of file, read
//! through `Read::take(limit + 1)`.
//!
//! All errors are [`std::io::Error`]s whose messages say what is wrong without repeating the
//! path; callers prefix it (`cannot write out/x.exr: it is a directory, …`).

use std::ffi::OsString;
use std::fs;
use std::io::{self, Error, ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Longest chain of symbolic links followed to find where a write lands (Linux's own limit).
pub const MAX_SYMLINKS: usize = 40;

/// What kind of file `file_type` is, with its article, for messages: `a directory`, `a FIFO`,
/// `a character device`, `a block device`, `a socket`, `a symbolic link`, `a regular file`.
pub fn file_kind(file_type: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if file_type.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if file_type.is_char_device() {
            return "a character device";
        }
        if file_type.is_block_device() {
            return "a block device";
        }
        if file_type.is_socket() {
            return "a socket";
        }
    }
    if file_type.is_dir() {
        "a directory"
    } else if file_type.is_symlink() {
        "a symbolic link"
    } else if file_type.is_file() {
        "a regular file"
    } else {
        "not a regular file"
    }
}

/// Reads the regular file at `path` (symbolic links followed), refusing what is not one and what
/// is larger than `limit` bytes. This is how gdsky reads every input: shaders, includes, images.
///
/// * A FIFO, a character or block device (`/dev/zero`), a socket or a directory is refused from
///   its metadata, *before* it is opened: opening a FIFO for reading blocks until a writer comes,
///   and a device can be endless. The error's kind is [`std::io::ErrorKind::InvalidInput`] (or
///   [`std::io::ErrorKind::IsADirectory`]), its message says what the path is.
/// * A file whose size is over `limit` is refused unread ([`std::io::ErrorKind::FileTooLarge`]).
///   The read itself goes through `Read::take(limit + 1)`, so a file that grows while it is read,
///   or one whose size the metadata does not tell (`/proc`), is refused after `limit + 1` bytes
///   rather than read to its end.
/// * After opening, the open file is checked again, so a path swapped for a device between the
///   check and the open is refused too. (One swapped for a FIFO in that window would block the
///   open; that needs a hostile process racing gdsky on a path the user gave.)
///
/// Other errors (missing file, permissions) are the operating system's.
pub fn read_limited(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind, Read};
    let refuse_kind = |meta: &std::fs::Metadata| -> std::io::Result<()> {
        let file_type = meta.file_type();
        if file_type.is_file() {
            return Ok(());
        }
        let kind = if file_type.is_dir() { ErrorKind::IsADirectory } else { ErrorKind::InvalidInput };
        Err(Error::new(
            kind,
            format!("it is {}, not a regular file (gdsky reads only regular files)", file_kind(&file_type)),
        ))
    };
    let too_large = |size: u64| {
        Error::new(ErrorKind::FileTooLarge, format!("it is {}, over the {} limit", byte_size(size), byte_size(limit)))
    };
    let meta = std::fs::metadata(path)?;
    refuse_kind(&meta)?;
    if meta.len() > limit {
        return Err(too_large(meta.len()));
    }
    let file = std::fs::File::open(path)?;
    let opened = file.metadata()?;
    refuse_kind(&opened)?;
    let mut bytes = Vec::with_capacity(usize::try_from(opened.len().min(limit)).unwrap_or(0));
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(opened.len().max(bytes.len() as u64)));
    }
    Ok(bytes)
}

/// `512 bytes`, `4 MiB`, `2.5 GiB`: a size for messages.
fn byte_size(bytes: u64) -> String {
    const UNITS: [&str; 4] = ["KiB", "MiB", "GiB", "TiB"];
    if bytes < 1024 {
        return format!("{bytes} bytes");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    let text = format!("{value:.1}");
    format!("{} {}", text.strip_suffix(".0").unwrap_or(&text), UNITS[unit])
}

/// The directory a path's file is in (`.` for a bare name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// True when the path is written with a trailing `/` or `/.`, or is `.` (it then names a
/// directory).
fn ends_with_separator(path: &Path) -> bool {
    let bytes = path.as_os_str().as_encoded_bytes();
    let separator = |b: &u8| *b == b'/' || (cfg!(windows) && *b == b'\\');
    match bytes {
        [.., b] if separator(b) => true,
        [.., b, b'.'] if separator(b) => true, // `dir/.`
        [b'.'] => true,
        _ => false,
    }
}

/// `it` for the path the user gave, `its link target T` for the end of a symlink chain.
fn subject(path: &Path, target: &Path) -> String {
    if path == target { "it".into() } else { format!("its link target {}", target.display()) }
}

/// Where a write to `path` lands: `path` itself when it is a regular file or absent, else the end
/// of its chain of symbolic links (relative links resolved from the link's directory), which must
/// be a regular file or absent. The directory of the result exists and is a directory. Refused,
/// with a message saying why: a directory, a FIFO, a device, a socket, a path ending in `/` or
/// naming no file (`..`), a missing directory, a loop of links.
pub fn resolve_output(path: &Path) -> io::Result<PathBuf> {
    if ends_with_separator(path) || path.file_name().is_none() {
        return Err(Error::new(ErrorKind::InvalidInput, "the path names a directory, not a file"));
    }
    let mut current = path.to_path_buf();
    for _ in 0..=MAX_SYMLINKS {
        match fs::symlink_metadata(&current) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let target = fs::read_link(&current)?;
                current = if target.is_absolute() { target } else { parent_dir(&current).join(target) };
                if current.file_name().is_none() {
                    return Err(Error::new(
                        ErrorKind::InvalidInput,
                        format!("its link target {} names a directory, not a file", current.display()),
                    ));
                }
            }
            Ok(meta) if meta.is_file() => return Ok(current),
            Ok(meta) => {
                let kind = if meta.is_dir() { ErrorKind::IsADirectory } else { ErrorKind::InvalidInput };
                return Err(Error::new(
                    kind,
                    format!(
                        "{} is {}, not a regular file (gdsky replaces only regular files)",
                        subject(path, &current),
                        file_kind(&meta.file_type())
                    ),
                ));
            }
            // Absent; or a component of the path is not a directory, which the parent's check
            // below reports.
            Err(err) if matches!(err.kind(), ErrorKind::NotFound | ErrorKind::NotADirectory) => {
                let dir = parent_dir(&current);
                return match fs::metadata(dir) {
                    Ok(meta) if meta.is_dir() => Ok(current),
                    Ok(meta) => Err(Error::new(
                        ErrorKind::NotADirectory,
                        format!("{} is {}, not a directory", dir.display(), file_kind(&meta.file_type())),
                    )),
                    Err(err) if err.kind() == ErrorKind::NotFound => {
                        Err(Error::new(ErrorKind::NotFound, format!("the directory {} does not exist", dir.display())))
                    }
                    Err(err) => {
                        Err(Error::new(err.kind(), format!("cannot use the directory {}: {err}", dir.display())))
                    }
                };
            }
            Err(err) => return Err(err),
        }
    }
    Err(Error::new(
        ErrorKind::InvalidInput,
        format!("more than {MAX_SYMLINKS} symbolic links in a row (a loop of links?)"),
    ))
}

/// A fresh, unused name for a temporary file next to `target`: dot-prefixed (hidden from `ls`),
/// with the process id and a counter, so concurrent writers (threads or processes) never share
/// one.
fn temporary_path(target: &Path, purpose: &str) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut name = OsString::from(".");
    name.push(target.file_name().unwrap_or_else(|| "gdsky".as_ref()));
    name.push(format!(".{}-{}.{purpose}", std::process::id(), COUNTER.fetch_add(1, Ordering::Relaxed)));
    parent_dir(target).join(name)
}

/// Removes the temporary files of `target` ([`temporary_path`]'s names) that a gdsky process
/// which no longer runs left behind (killed between writing and renaming). Only on Linux, where
/// `/proc` says which processes run; elsewhere they stay. Best effort: a file that cannot be
/// removed is left.
fn remove_stale_temporaries(target: &Path) {
    if !cfg!(target_os = "linux") || !Path::new("/proc/self").exists() {
        return;
    }
    let Some(name) = target.file_name() else { return };
    let mut prefix = OsString::from(".");
    prefix.push(name);
    prefix.push(".");
    let Some(prefix) = prefix.to_str().map(str::to_owned) else { return };
    let Ok(entries) = fs::read_dir(parent_dir(target)) else { return };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(rest) = file_name.to_str().and_then(|n| n.strip_prefix(&prefix)) else { continue };
        // `{pid}-{counter}.{tmp|probe}`
        let Some((ids, purpose)) = rest.rsplit_once('.') else { continue };
        let Some((pid, counter)) = ids.split_once('-') else { continue };
        let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
        let ours = matches!(purpose, "tmp" | "probe") && digits(pid) && digits(counter);
        if ours && !Path::new("/proc").join(pid).exists() && entry.file_type().is_ok_and(|t| t.is_file()) {
            let _ = fs::remove_file(entry.path());
        }
    }
}

/// Creates (exclusively: never through a link, never over a stale file) the temporary file.
fn create_temporary(tmp: &Path) -> io::Result<fs::File> {
    fs::OpenOptions::new().write(true).create_new(true).open(tmp).map_err(|err| {
        Error::new(err.kind(), format!("cannot create a temporary file in {}: {err}", parent_dir(tmp).display()))
    })
}

/// Checks, before any work, that [`write_atomically`] to `path` can succeed: the rules of the
/// module documentation, and a temporary file created and removed in the destination's
/// directory. Returns where the write will land (the end of the symlink chain).
pub fn check_output(path: &Path) -> io::Result<PathBuf> {
    let target = resolve_output(path)?;
    let probe = temporary_path(&target, "probe");
    create_temporary(&probe)?;
    let _ = fs::remove_file(&probe);
    Ok(target)
}

/// Bytes free to an unprivileged writer on the file system holding `dir` (`statvfs`'s
/// `f_bavail × f_frsize`); `None` where the platform or the path does not say. For estimates
/// made before long work (`gdsky animate`), never for correctness: the space can change at once.
pub fn available_space(dir: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let stat = rustix::fs::statvfs(dir).ok()?;
        Some(stat.f_bavail.saturating_mul(stat.f_frsize))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}

/// `path` with `.` and `..` resolved lexically (no file is touched, links are not followed): the
/// form in which a path is compared with the folder it must stay in. A `..` above a root stays
/// at the root; leading `..` of a relative path are kept.
pub fn normalize(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => match out.components().next_back() {
                Some(Component::Normal(_)) => {
                    out.pop();
                }
                Some(Component::RootDir | Component::Prefix(_)) => {}
                _ => out.push(".."),
            },
            other => out.push(other.as_os_str()),
        }
    }
    out
}

/// Whether `a` and `b` name the same existing file, through any symbolic or hard link (the same
/// device and inode). An output that is an input would be destroyed by the write that makes it:
/// commands refuse it before any work.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (fs::metadata(a), fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (fs::canonicalize(a), fs::canonicalize(b)) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        }
    }
}

/// Checks, before any work, that `dir` can hold a command's outputs: an existing directory (links
/// followed) in which a file can be created, or, when `create` is true (the command creates its
/// output folder), a path whose nearest existing ancestor is such a directory. Nothing is created
/// (a failed run leaves no empty folder behind); [`create_output_dir`] does it when the outputs
/// are ready.
pub fn check_output_dir(dir: &Path, create: bool) -> io::Result<()> {
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    let mut existing = dir;
    loop {
        match fs::metadata(existing) {
            Ok(meta) if meta.is_dir() => break,
            Ok(meta) => {
                return Err(Error::new(
                    ErrorKind::NotADirectory,
                    format!("{} is {}, not a directory", existing.display(), file_kind(&meta.file_type())),
                ));
            }
            Err(err) if matches!(err.kind(), ErrorKind::NotFound | ErrorKind::NotADirectory) && create => {
                existing = match existing.parent() {
                    Some(parent) if !parent.as_os_str().is_empty() => parent,
                    _ => Path::new("."),
                };
            }
            Err(err) if err.kind() == ErrorKind::NotFound => {
                return Err(Error::new(ErrorKind::NotFound, format!("the directory {} does not exist", dir.display())));
            }
            Err(err) => return Err(Error::new(err.kind(), format!("cannot use {}: {err}", existing.display()))),
        }
    }
    let probe = temporary_path(&existing.join("gdsky"), "probe");
    create_temporary(&probe)?;
    let _ = fs::remove_file(&probe);
    Ok(())
}

/// Creates the output folder `dir` and its parents where missing (what `convert`, `demo`,
/// `bench` and `stress` promise for `-o DIR`); an existing directory, or a link to one, is fine.
pub fn create_output_dir(dir: &Path) -> io::Result<()> {
    fs::create_dir_all(dir).map_err(|err| Error::new(err.kind(), format!("cannot create the directory: {err}")))?;
    match fs::metadata(dir) {
        Ok(meta) if meta.is_dir() => Ok(()),
        Ok(meta) => Err(Error::new(ErrorKind::NotADirectory, format!("it is {}", file_kind(&meta.file_type())))),
        Err(err) => Err(err),
    }
}

/// Writes `bytes` to `path` atomically, with the policy of the module documentation: through
/// symbolic links to their target, over a regular file (keeping its permission bits) or into a
/// new one, never over a directory, device, FIFO or socket; nothing is left behind on failure.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> io::Result<()> {
    stage(path, bytes)?.commit()
}

/// Writes several files as a set: every file is first written and flushed to a temporary file
/// beside its target ([`write_atomically`]'s rules for each), and only when all of them are on
/// disk are they renamed into place, in order. A failure while writing (a full disk, a path
/// refused) removes every temporary file and leaves every target as it was. Each rename is
/// atomic, but the set's renames follow each other: a crash between two leaves the first new
/// and the rest old. While the renames run, each target folder is locked (an advisory `flock`
/// on the folder itself, best effort), so two gdsky processes writing sets into one folder
/// commit one whole set after the other, never a mix of both.
pub fn write_set(files: &[(&Path, &[u8])]) -> io::Result<()> {
    let staged = files.iter().map(|(path, bytes)| stage(path, bytes)).collect::<io::Result<Vec<_>>>()?;
    let mut folders: Vec<PathBuf> = staged.iter().map(|f| parent_dir(&f.target).to_path_buf()).collect();
    // One order for every process, so two sets over the same folders cannot deadlock.
    folders.sort();
    folders.dedup();
    // Held until the renames are done; dropping a file releases its lock.
    let _locks: Vec<fs::File> =
        folders.iter().filter_map(|dir| fs::File::open(dir).ok()).filter(|dir| dir.lock().is_ok()).collect();
    for file in staged {
        file.commit()?;
    }
    Ok(())
}

/// A file written to its temporary name, waiting to be renamed over its target; dropped
/// uncommitted, the temporary file is removed.
struct Staged<'a> {
    path: &'a Path,
    target: PathBuf,
    tmp: PathBuf,
    committed: bool,
}

/// Writes `bytes` to a temporary file beside where `path` lands, flushed to disk.
fn stage<'a>(path: &'a Path, bytes: &[u8]) -> io::Result<Staged<'a>> {
    let target = resolve_output(path)?;
    remove_stale_temporaries(&target);
    let tmp = temporary_path(&target, "tmp");
    let mut file = create_temporary(&tmp)?;
    let staged = Staged { path, target, tmp, committed: false };
    file.write_all(bytes)?;
    if let Ok(old) = fs::metadata(&staged.target) {
        // The new file keeps the old one's mode (a 0600 key file stays private). Owner and
        // group cannot be kept without privileges; the new file is the writer's.
        let _ = file.set_permissions(old.permissions());
    }
    file.sync_all()?;
    // Closed before the rename, which Windows requires.
    drop(file);
    Ok(staged)
}

impl Staged<'_> {
    /// Renames the temporary file over the target.
    fn commit(mut self) -> io::Result<()> {
        // Checked again: a special file put there since the write started is not replaced.
        if let Ok(meta) = fs::symlink_metadata(&self.target)
            && !meta.is_file()
        {
            return Err(Error::new(
                ErrorKind::InvalidInput,
                format!(
                    "{} became {} during the write; not replaced",
                    subject(self.path, &self.target),
                    file_kind(&meta.file_type())
                ),
            ));
        }
        fs::rename(&self.tmp, &self.target)
            .map_err(|err| Error::new(err.kind(), format!("cannot rename the temporary file into place: {err}")))?;
        self.committed = true;
        // The rename is durable once the directory is flushed too (best effort: not every
        // platform or file system lets a directory be opened and synced).
        #[cfg(unix)]
        if let Ok(dir) = fs::File::open(parent_dir(&self.target)) {
            let _ = dir.sync_all();
        }
        Ok(())
    }
}

impl Drop for Staged<'_> {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_file(&self.tmp);
        }
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::unix::fs::{FileTypeExt, PermissionsExt, symlink};

    /// The names in `dir`, sorted.
    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<_> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        names.sort();
        names.into_iter().map(|n| n.to_string_lossy().into_owned()).collect()
    }

    fn mkfifo(path: &Path) {
        let status = std::process::Command::new("mkfifo").arg(path).status().unwrap();
        assert!(status.success());
    }

    /// A temporary file left by a killed writer (its process gone) is removed by the next write
    /// of the same target; one of a running writer, and other files, are kept.
    #[test]
    fn stale_temporaries_of_dead_writers_are_cleaned_up() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("sky.exr");
        // PID 4194304 is above Linux's largest (2^22): never a running process.
        let stale = dir.path().join(".sky.exr.4194304-0.tmp");
        let running = dir.path().join(format!(".sky.exr.{}-99.tmp", std::process::id()));
        let other = dir.path().join(".other.exr.4194304-0.tmp");
        for f in [&stale, &running, &other] {
            fs::write(f, b"partial").unwrap();
        }
        write_atomically(&target, b"new").unwrap();
        assert_eq!(
            entries(dir.path()),
            vec![
                ".other.exr.4194304-0.tmp".to_string(),
                running.file_name().unwrap().to_string_lossy().into_owned(),
                "sky.exr".into()
            ]
        );
    }

    #[test]
    fn writes_and_replaces_regular_files_keeping_their_mode() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        write_atomically(&path, b"one").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"one");
        fs::set_permissions(&path, fs::Permissions::from_mode(0o600)).unwrap();
        write_atomically(&path, b"two, longer").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"two, longer");
        assert_eq!(fs::metadata(&path).unwrap().permissions().mode() & 0o777, 0o600);
        assert_eq!(check_output(&path).unwrap(), path);
        assert_eq!(entries(dir.path()), ["a.txt"], "no temporary or probe files left");
    }

    #[test]
    fn refuses_directories_fifos_sockets_and_devices_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("sub");
        fs::create_dir(&sub).unwrap();
        let fifo = dir.path().join("fifo");
        mkfifo(&fifo);
        let socket = dir.path().join("socket");
        let _listener = std::os::unix::net::UnixListener::bind(&socket).unwrap();
        for (path, what) in [(&sub, "a directory"), (&fifo, "a FIFO"), (&socket, "a socket")] {
            for err in [write_atomically(path, b"x").unwrap_err(), check_output(path).unwrap_err()] {
                let message = err.to_string();
                assert!(message.contains(what) && message.contains("not a regular file"), "{message}");
            }
        }
        assert!(fs::metadata(&sub).unwrap().is_dir());
        assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
        assert!(fs::symlink_metadata(&socket).unwrap().file_type().is_socket());
        // A device, reached through a link so that nothing in /dev is ever the write's target.
        let device = dir.path().join("null-link");
        symlink("/dev/null", &device).unwrap();
        let err = write_atomically(&device, b"x").unwrap_err().to_string();
        assert!(err.contains("its link target /dev/null is a character device"), "{err}");
        assert!(fs::metadata("/dev/null").unwrap().file_type().is_char_device());
        // A trailing slash names a directory, existing or not.
        let dir_text = dir.path().display();
        for text in [format!("{dir_text}/new/"), format!("{dir_text}/.."), format!("{dir_text}/new/.")] {
            let err = write_atomically(Path::new(&text), b"x").unwrap_err().to_string();
            assert!(err.contains("names a directory"), "{text}: {err}");
        }
        assert_eq!(entries(dir.path()), ["fifo", "null-link", "socket", "sub"]);
    }

    #[test]
    fn writes_through_symlinks_and_keeps_them() {
        let dir = tempfile::tempdir().unwrap();
        let runs = dir.path().join("runs");
        fs::create_dir(&runs).unwrap();
        fs::write(runs.join("run42.exr"), b"old").unwrap();
        // latest -> runs/run42.exr (relative), alias -> latest (absolute): a chain of two.
        let latest = dir.path().join("latest.exr");
        symlink("runs/run42.exr", &latest).unwrap();
        let alias = dir.path().join("alias.exr");
        symlink(&latest, &alias).unwrap();
        assert_eq!(check_output(&alias).unwrap(), runs.join("run42.exr"));
        write_atomically(&alias, b"new").unwrap();
        assert!(fs::symlink_metadata(&alias).unwrap().file_type().is_symlink());
        assert!(fs::symlink_metadata(&latest).unwrap().file_type().is_symlink());
        assert_eq!(fs::read(runs.join("run42.exr")).unwrap(), b"new");
        assert_eq!(fs::read_dir(&runs).unwrap().count(), 1, "the temporary file was in the target's directory");

        // A dangling link to a missing file in an existing directory: the file is created.
        let dangling = dir.path().join("next.exr");
        symlink("runs/run43.exr", &dangling).unwrap();
        write_atomically(&dangling, b"43").unwrap();
        assert_eq!(fs::read(runs.join("run43.exr")).unwrap(), b"43");
        assert!(fs::symlink_metadata(&dangling).unwrap().file_type().is_symlink());

        // Dangling into a missing directory, a link to a directory, a loop: refused.
        let nowhere = dir.path().join("nowhere.exr");
        symlink("missing/run.exr", &nowhere).unwrap();
        let err = write_atomically(&nowhere, b"x").unwrap_err();
        assert_eq!(err.kind(), ErrorKind::NotFound);
        assert!(err.to_string().contains("missing does not exist"), "{err}");
        let to_dir = dir.path().join("to-dir.exr");
        symlink("runs", &to_dir).unwrap();
        let err = write_atomically(&to_dir, b"x").unwrap_err().to_string();
        assert!(err.contains("its link target") && err.contains("is a directory"), "{err}");
        let (a, b) = (dir.path().join("loop-a"), dir.path().join("loop-b"));
        symlink("loop-b", &a).unwrap();
        symlink("loop-a", &b).unwrap();
        assert!(write_atomically(&a, b"x").unwrap_err().to_string().contains("symbolic links in a row"));
        assert!(fs::symlink_metadata(&to_dir).unwrap().file_type().is_symlink());
    }

    #[test]
    fn missing_and_unusable_directories() {
        let dir = tempfile::tempdir().unwrap();
        let err = check_output(&dir.path().join("no/such/file.exr")).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::NotFound);
        assert!(err.to_string().contains("no/such does not exist"), "{err}");
        fs::write(dir.path().join("file"), b"").unwrap();
        let err = check_output(&dir.path().join("file/x.exr")).unwrap_err().to_string();
        assert!(err.contains("is a regular file, not a directory"), "{err}");

        // An output folder: missing is fine when the command creates it, under a directory.
        let out = dir.path().join("out/nested");
        check_output_dir(&out, true).unwrap();
        assert!(!dir.path().join("out").exists(), "the check creates nothing");
        let err = check_output_dir(&out, false).unwrap_err().to_string();
        assert!(err.contains("does not exist"), "{err}");
        let err = check_output_dir(&dir.path().join("file/out"), true).unwrap_err().to_string();
        assert!(err.contains("is a regular file, not a directory"), "{err}");
        create_output_dir(&out).unwrap();
        check_output_dir(&out, false).unwrap();
        assert!(create_output_dir(&dir.path().join("file")).is_err());
        assert_eq!(entries(dir.path()), ["file", "out"]);
    }

    #[test]
    fn read_limited_refuses_special_and_large_files() {
        let dir = tempfile::tempdir().unwrap();
        let small = dir.path().join("small");
        fs::write(&small, b"0123456789").unwrap();
        assert_eq!(read_limited(&small, 10).unwrap(), b"0123456789");
        let err = read_limited(&small, 9).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::FileTooLarge);
        assert!(err.to_string().contains("10 bytes, over the 9 bytes limit"), "{err}");
        // A sparse 5 GiB file: refused from its size, nothing read.
        let big = dir.path().join("big");
        fs::File::create(&big).unwrap().set_len(5 << 30).unwrap();
        let err = read_limited(&big, 4 << 20).unwrap_err().to_string();
        assert!(err.contains("5 GiB, over the 4 MiB limit"), "{err}");
        // A FIFO (no writer: opening it would block), a device without end, a directory.
        let fifo = dir.path().join("fifo");
        mkfifo(&fifo);
        let err = read_limited(&fifo, 1 << 20).unwrap_err().to_string();
        assert!(err.contains("a FIFO (named pipe), not a regular file"), "{err}");
        let err = read_limited(Path::new("/dev/zero"), 1 << 20).unwrap_err().to_string();
        assert!(err.contains("a character device"), "{err}");
        assert_eq!(read_limited(dir.path(), 1 << 20).unwrap_err().kind(), ErrorKind::IsADirectory);
        // A regular file whose metadata says 0 bytes but which has more: bounded by `take`.
        let status = fs::read("/proc/self/status");
        if status.as_ref().is_ok_and(|s| s.len() > 64) {
            let err = read_limited(Path::new("/proc/self/status"), 64).unwrap_err();
            assert_eq!(err.kind(), ErrorKind::FileTooLarge);
        }
    }
}
