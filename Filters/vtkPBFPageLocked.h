// Page-locked ("pinned") host memory for the output arrays when the solver runs on CUDA: the GPU
// copies into it at the full bus speed, where ordinary (pageable) memory is staged by the driver
// at a fraction of it (Documentation/Performance.md has both). Internal to PBF::Filters.
//
// VTK releases an array's memory through a plain function pointer (SetArrayFreeFunction) that
// only gets the pointer, so the pool is one per process: a released buffer is kept for the next
// frame of the same size instead of being unpinned (pinning costs milliseconds). The pool is
// bounded: past PBF_PAGE_LOCKED_LIMIT bytes in use Allocate() returns null and the caller falls
// back to ordinary memory, so that views caching many frames cannot pin the host's memory.
#ifndef vtkPBFPageLocked_h
#define vtkPBFPageLocked_h

#include <cstddef>

namespace vtkPBFPageLocked
{

// True when this build has the CUDA runtime (the pool can pin memory).
bool Available();

// size bytes of page-locked memory, or null (no CUDA runtime, no device, or the limit reached).
void* Allocate(std::size_t size);

// Gives memory from Allocate back to the pool; the function VTK arrays call when they let go.
void Release(void* memory);

// Bytes handed out and not yet released, and bytes kept for reuse.
std::size_t BytesInUse();
std::size_t BytesPooled();

} // namespace vtkPBFPageLocked

#endif
