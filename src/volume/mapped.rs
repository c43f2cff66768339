//! Files mapped into memory, and what happens when one shrinks under the map.
//!
//! Uncompressed voxels stored as they are held are read in place from a read-only map of their
//! file (docs/formats.md, "How voxels are held"): no copy, and pages the kernel can drop. The
//! price of a map is that another process may truncate the file while it is mapped; reading a
//! page past the new end then raises SIGBUS, which would kill the process without a word. So
//! every map is registered here with a one-line message naming its file, and
//! [`install_fault_handler`] (which the `slabscope` binary calls at start) turns SIGBUS on a
//! registered map into that line on stderr and exit status 1. A library user who does not call it
//! gets the default action of SIGBUS (the process ends) in that case.
//!
//! A host process that must live on (the Python module: the interpreter is the user's notebook)
//! calls [`install_fault_recovery`] instead: a fault in a registered map puts a page of zeros in
//! place of the page that is gone and marks the map cut short, the read goes on, and the caller
//! asks [`MappedFile::check`] (through `Volume::check_intact`) after the work, which then fails
//! naming the file.

#![allow(unsafe_code)]

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicUsize, Ordering};

use crate::error::{Error, Result};

/// A read-only memory map shared by the volumes (and pyramid levels) made from one file,
/// registered so that its file being cut short is reported (see the module's documentation).
pub struct MappedFile {
    map: memmap2::Mmap,
    slot: Option<usize>,
    path: PathBuf,
    scratch: bool,
}

impl MappedFile {
    /// Wraps a map of the whole file at `path`, registered in `slot`.
    fn new(map: memmap2::Mmap, slot: Option<usize>, path: &Path, scratch: bool) -> Arc<Self> {
        Arc::new(Self {
            map,
            slot,
            path: path.to_path_buf(),
            scratch,
        })
    }

    /// Whether this is a scratch file the voxels of `path` were decoded into (beyond the memory
    /// budget), rather than `path` itself.
    #[must_use]
    pub fn is_scratch(&self) -> bool {
        self.scratch
    }

    /// The mapped bytes.
    #[must_use]
    pub fn bytes(&self) -> &[u8] {
        &self.map
    }

    /// Fails, naming the file, when it was cut short under the map and a read found a page gone
    /// (replaced with zeros by [`install_fault_recovery`]'s handler): what was computed from it
    /// is wrong.
    pub fn check(&self) -> Result<()> {
        let cut = self
            .slot
            .is_some_and(|i| SLOTS_IN_USE[i].cut.load(Ordering::Acquire));
        if cut {
            return Err(Error::format(
                &self.path,
                "the file was cut short while slabscope was reading it (it is mapped into \
                 memory, and another program truncated it): load it again",
            ));
        }
        Ok(())
    }
}

impl Drop for MappedFile {
    fn drop(&mut self) {
        if let Some(slot) = self.slot {
            unregister(slot);
        }
    }
}

impl std::fmt::Debug for MappedFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MappedFile({} bytes)", self.map.len())
    }
}

/// Maps registered at once: more maps than this are simply not registered (a fault in one of
/// them gets the default action).
const SLOTS: usize = 256;

/// A registered map: its address range and the message that names its file (a leaked
/// `Box<[u8]>`, freed when the map is dropped).
struct Slot {
    start: AtomicUsize,
    len: AtomicUsize,
    message: AtomicPtr<u8>,
    message_len: AtomicUsize,
    /// A fault found a page of the map gone (with recovery on).
    cut: AtomicBool,
}

#[allow(clippy::declare_interior_mutable_const)]
const FREE: Slot = Slot {
    start: AtomicUsize::new(0),
    len: AtomicUsize::new(0),
    message: AtomicPtr::new(std::ptr::null_mut()),
    message_len: AtomicUsize::new(0),
    cut: AtomicBool::new(false),
};

/// Whether a fault in a registered map is recovered from ([`install_fault_recovery`]), and the
/// page size the handler replaces pages by (read before, not in, the handler).
static RECOVER: AtomicBool = AtomicBool::new(false);
static PAGE: AtomicUsize = AtomicUsize::new(0);

static SLOTS_IN_USE: [Slot; SLOTS] = [FREE; SLOTS];

/// Maps `file` (opened from `path`) read-only and registers the map, so that a fault in it is
/// reported naming `path`.
pub(crate) fn map(file: &File, path: &Path) -> std::io::Result<Arc<MappedFile>> {
    // SAFETY: the map is read-only. Another process may truncate the file while it is mapped;
    // a read of a page past the new end then raises SIGBUS, which `install_fault_handler`
    // reports (see the module documentation). Writes by others show through, which is no
    // memory-safety matter for plain numbers.
    let map = unsafe { memmap2::Mmap::map(file) }?;
    let slot = register(&map, path);
    Ok(MappedFile::new(map, slot, path, false))
}

/// The read-only map of an unnamed scratch file in `dir` the voxels of `path` were decoded
/// into, registered so that a page the disk fails to give back is reported as the other maps'
/// faults are.
pub(crate) fn scratch(map: memmap2::Mmap, path: &Path, dir: &Path) -> Arc<MappedFile> {
    let text = format!(
        "slabscope: error: {}: its voxels decoded into a scratch file in {} could not be read \
         back (the disk failed, or the file was cut short)\n",
        crate::error::shown(path),
        crate::error::shown(dir)
    );
    let slot = register_text(&map, text);
    MappedFile::new(map, slot, path, true)
}

/// Registers the range of `map`; the slot taken, if any.
fn register(map: &memmap2::Mmap, path: &Path) -> Option<usize> {
    let text = format!(
        "slabscope: error: {}: the file was cut short while slabscope was reading it (it is \
         mapped into memory, and another program truncated it)\n",
        crate::error::shown(path)
    );
    register_text(map, text)
}

/// Registers the range of `map` with the line `text` a fault in it prints.
fn register_text(map: &memmap2::Mmap, text: String) -> Option<usize> {
    if map.is_empty() {
        return None;
    }
    let message: Box<[u8]> = text.into_bytes().into_boxed_slice();
    let message_len = message.len();
    let message = Box::into_raw(message).cast::<u8>();
    for (i, slot) in SLOTS_IN_USE.iter().enumerate() {
        if slot
            .start
            .compare_exchange(0, usize::MAX, Ordering::AcqRel, Ordering::Relaxed)
            .is_ok()
        {
            slot.message.store(message, Ordering::Release);
            slot.message_len.store(message_len, Ordering::Release);
            slot.cut.store(false, Ordering::Release);
            slot.len.store(map.len(), Ordering::Release);
            slot.start.store(map.as_ptr() as usize, Ordering::Release);
            return Some(i);
        }
    }
    // SAFETY: `message` came from `Box::into_raw` of a slice of this length just above and was
    // not stored anywhere.
    drop(unsafe { Box::from_raw(std::ptr::slice_from_raw_parts_mut(message, message_len)) });
    None
}

/// Frees slot `i`, taken by [`register`], before its map is dropped.
fn unregister(i: usize) {
    let slot = &SLOTS_IN_USE[i];
    slot.start.store(usize::MAX, Ordering::Release);
    let message = slot.message.swap(std::ptr::null_mut(), Ordering::AcqRel);
    let len = slot.message_len.load(Ordering::Acquire);
    if !message.is_null() {
        // SAFETY: `register` stored a pointer from `Box::into_raw` of a slice of `len` bytes, and
        // the swap above took it out, so it is freed once.
        drop(unsafe { Box::from_raw(std::ptr::slice_from_raw_parts_mut(message, len)) });
    }
    slot.start.store(0, Ordering::Release);
}

/// The slot of the registered map holding `address`.
fn slot_for(address: usize) -> Option<&'static Slot> {
    SLOTS_IN_USE.iter().find(|slot| {
        let start = slot.start.load(Ordering::Acquire);
        let len = slot.len.load(Ordering::Acquire);
        start != 0 && start != usize::MAX && (start..start + len).contains(&address)
    })
}

/// The message of `slot`, as a pointer and length, while it is registered.
fn message_of(slot: &Slot) -> Option<(*const u8, usize)> {
    let message = slot.message.load(Ordering::Acquire);
    (!message.is_null()).then(|| {
        (
            message.cast_const(),
            slot.message_len.load(Ordering::Acquire),
        )
    })
}

/// Installs the SIGBUS handler that reports a fault in a registered map (a file truncated while
/// mapped) as one line naming the file on stderr and ends the process with status 1. A SIGBUS
/// anywhere else gets the default action, as without the handler. Call it once, early.
pub fn install_fault_handler() {
    // SAFETY: a zeroed sigaction is a valid value; the handler only reads atomics, calls write(2)
    // and _exit(2), which are async-signal-safe, or restores the default action and returns so
    // that the fault repeats under it.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = on_fault as *const () as usize;
        action.sa_flags = libc::SA_SIGINFO;
        libc::sigemptyset(&raw mut action.sa_mask);
        libc::sigaction(libc::SIGBUS, &raw const action, std::ptr::null_mut());
    }
}

/// [`install_fault_handler`], except that a fault in a registered map is recovered from: the
/// page that is gone is replaced with a page of zeros and the map marked cut short, for
/// [`MappedFile::check`] to report (see the module's documentation). For a host process that
/// must not end (the Python module).
pub fn install_fault_recovery() {
    // SAFETY: sysconf is safe to call; a failure gives -1, and then no page is replaced.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    PAGE.store(usize::try_from(page).unwrap_or(0), Ordering::Release);
    RECOVER.store(true, Ordering::Release);
    install_fault_handler();
}

extern "C" fn on_fault(signal: libc::c_int, info: *mut libc::siginfo_t, _: *mut libc::c_void) {
    // SAFETY: the kernel passes a valid siginfo for a handler installed with SA_SIGINFO.
    let address = unsafe { (*info).si_addr() } as usize;
    if let Some(slot) = slot_for(address) {
        let page = PAGE.load(Ordering::Acquire);
        if RECOVER.load(Ordering::Acquire) && page.is_power_of_two() {
            // SAFETY: the page lies inside a registered read-only map of ours, which stays
            // mapped while registered; MAP_FIXED replaces just that page with zeros (mmap is a
            // plain system call, safe in a handler on Linux), and the faulting read then
            // repeats on it.
            let zeros = unsafe {
                libc::mmap(
                    (address & !(page - 1)) as *mut libc::c_void,
                    page,
                    libc::PROT_READ,
                    libc::MAP_PRIVATE | libc::MAP_ANONYMOUS | libc::MAP_FIXED,
                    -1,
                    0,
                )
            };
            if zeros != libc::MAP_FAILED {
                slot.cut.store(true, Ordering::Release);
                return;
            }
        }
        if let Some((message, len)) = message_of(slot) {
            // SAFETY: the message is a live allocation of `len` bytes (freed only after its
            // slot is cleared); write and _exit are async-signal-safe.
            unsafe {
                libc::write(2, message.cast(), len);
                libc::_exit(1);
            }
        }
    }
    // SAFETY: restoring the default action is async-signal-safe; returning re-runs the faulting
    // instruction, which then ends the process as SIGBUS always has.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message_for(address: usize) -> Option<(*const u8, usize)> {
        slot_for(address).and_then(message_of)
    }

    #[test]
    fn maps_are_registered_until_dropped() {
        let mut file = tempfile::NamedTempFile::new().unwrap();
        std::io::Write::write_all(&mut file, &[7u8; 100]).unwrap();
        let mapped = map(file.as_file(), file.path()).unwrap();
        let start = mapped.bytes().as_ptr() as usize;
        let (message, len) = message_for(start + 50).expect("registered");
        // SAFETY: the map is alive, so its message is.
        let text = unsafe { std::slice::from_raw_parts(message, len) };
        let text = String::from_utf8(text.to_vec()).unwrap();
        assert!(text.contains(&file.path().display().to_string()), "{text}");
        assert!(text.ends_with('\n') && text.matches('\n').count() == 1);
        assert!(message_for(start + 100).is_none(), "one past the end");
        drop(mapped);
        assert!(
            message_for(start + 50).is_none(),
            "unregistered when dropped"
        );
    }

    /// With recovery on, a read past the end of a file cut short under its map finds zeros
    /// instead of ending the process, and the map then says it was cut short, naming the file.
    #[test]
    fn a_file_cut_short_under_its_map_is_recovered_from_and_reported() {
        install_fault_recovery();
        let page = PAGE.load(Ordering::Acquire);
        let mut file = tempfile::NamedTempFile::new().unwrap();
        std::io::Write::write_all(&mut file, &vec![7u8; 3 * page]).unwrap();
        let mapped = map(file.as_file(), file.path()).unwrap();
        assert!(mapped.check().is_ok());
        file.as_file().set_len(page as u64).unwrap();
        let bytes = mapped.bytes();
        assert_eq!(std::hint::black_box(bytes[10]), 7, "the page still there");
        let gone = std::hint::black_box(&bytes[2 * page + 10]);
        // SAFETY: a read of a mapped byte; the page past the end faults and is replaced.
        assert_eq!(unsafe { std::ptr::read_volatile(gone) }, 0);
        let e = mapped.check().unwrap_err().to_string();
        assert!(e.contains(&file.path().display().to_string()), "{e}");
        assert!(e.contains("cut short"), "{e}");
    }
}
