//! Traversal memory on transparent huge pages. Incoherent rays on a large mesh
//! touch nodes and leaf blocks all over tens of megabytes: with 4 kB pages most
//! of those touches also miss the TLB. Embree asks the kernel for huge pages
//! (`madvise(MADV_HUGEPAGE)`) on its tree; so does this.

/// An empty vector with room for `capacity` elements whose memory is advised for
/// huge pages before anything is written to it (the kernel picks the page size
/// when a page is first touched).
pub(crate) fn huge_page_vec<T>(capacity: usize) -> Vec<T> {
    let v: Vec<T> = Vec::with_capacity(capacity);
    advise(v.as_ptr().cast(), capacity * std::mem::size_of::<T>());
    v
}

/// A copy of `items` in memory advised for huge pages, exactly as long.
pub(crate) fn on_huge_pages<T: Copy>(items: &[T]) -> Vec<T> {
    let mut v = huge_page_vec(items.len());
    v.extend_from_slice(items);
    v
}

/// Advises the whole 2 MB pages inside `[start, start + bytes)`; smaller ranges
/// cannot hold one and are left alone. Only a hint: failure changes nothing.
fn advise(start: *const u8, bytes: usize) {
    const HUGE: usize = 2 << 20;
    #[cfg(target_os = "linux")]
    {
        let begin = (start as usize).next_multiple_of(HUGE);
        let end = (start as usize + bytes) / HUGE * HUGE;
        if end > begin {
            // SAFETY: the range lies inside one live allocation; the advice
            // changes how pages are backed, never their contents.
            unsafe { libc::madvise(begin as *mut libc::c_void, end - begin, libc::MADV_HUGEPAGE) };
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (start, bytes, HUGE);
}
