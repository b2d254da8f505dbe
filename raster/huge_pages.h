#pragma once
// Transparent huge pages for the renderer's large buffers.
//
// A process that renders one image takes every page of its buffers fresh from the kernel: the
// dragon at 1080p faulted 36,000 4 KiB pages, a third of its CPU time in the fault handler on this
// VM. Linux backs a range marked MADV_HUGEPAGE with 2 MiB pages where it can, one fault each
// instead of 512 (Debian's default is `madvise`: only marked ranges get them). Advising the
// buffers of kHugePageAdviceBytes or more (vertex outputs, framebuffer, resolved image, the PLY
// loader's arrays): `cuberille render dragon_vrip.binary.ply --width 1920 --height 1080`, eight
// alternating runs, 36,000 -> 16,000 faults and 154-160 -> 129-136 ms spawn to exit. Most faults
// left are the front end's batches (4,096 triangles' set-up records and varyings, 557 KiB each),
// too small to hold a 2 MiB page of their own.
//
// Only advice: where the kernel has no huge page free or THP is off, the range stays in 4 KiB
// pages; nothing else changes, and no result depends on it.

#include <cstddef>

namespace cuberille::raster {

/// Buffers of at least this many bytes are advised: the 2 MiB-aligned part of a smaller one is
/// at most a page or two, not worth a system call (and a 2 MiB page holds memory a small buffer
/// may never touch).
inline constexpr size_t kHugePageAdviceBytes = size_t(4) << 20;

/// Marks the whole 2 MiB pages inside [data, data + bytes) for huge pages, when bytes is at
/// least kHugePageAdviceBytes and the system has them; call it before the buffer is first
/// written, since pages already faulted stay small.
void adviseHugePages(void* data, size_t bytes);

/// v.reserve(n), with storage it newly allocates advised before anything is written to it.
template <class Vector>
void reserveAdvised(Vector& v, size_t n) {
    if (n <= v.capacity()) return;
    v.reserve(n);
    adviseHugePages(v.data(), v.capacity() * sizeof(typename Vector::value_type));
}

/// v.resize(n, value...), likewise: a vector's resize writes its new elements, and advice after
/// that is too late.
template <class Vector, class... Value>
void resizeAdvised(Vector& v, size_t n, const Value&... value) {
    reserveAdvised(v, n);
    v.resize(n, value...);
}

}  // namespace cuberille::raster
