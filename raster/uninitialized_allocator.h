#pragma once
// An allocator whose resize() leaves new elements default-initialised: for trivial types,
// unwritten. For buffers a parallel stage writes in full right after sizing them (the vertex
// stage's outputs, the resolved image): value-initialisation would first write every byte on
// one thread, and in a fresh process take every page fault there (a 1080p float image is 33 MB,
// 8,000 faults, 8-10 ms), where the stage's own threads would take them in parallel. Large ones
// are advised for huge pages as they are allocated (raster/huge_pages.h), before any is written.

#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

#include "raster/huge_pages.h"

namespace cuberille::raster {

template <class T>
struct UninitializedAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = UninitializedAllocator<U>;
    };
    UninitializedAllocator() = default;
    template <class U>
    UninitializedAllocator(const UninitializedAllocator<U>&) {}
    T* allocate(std::size_t n) {
        T* p = std::allocator<T>::allocate(n);
        adviseHugePages(p, n * sizeof(T));
        return p;
    }
    template <class U>
    void construct(U* p) noexcept {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

/// A vector sized without writing its elements (see above).
template <class T>
using UninitializedVector = std::vector<T, UninitializedAllocator<T>>;

}  // namespace cuberille::raster
