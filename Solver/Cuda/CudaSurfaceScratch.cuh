// The GPU surface's device arrays (CudaSurface.cu): each grows and never shrinks, so that the
// extractor keeps its memory from frame to frame. Included by CudaSurface.cu alone, in an
// anonymous namespace as the rest of that file's helpers.
#pragma once

#include "CudaRuntime.cuh"

#include <cuda_runtime.h>

#include <algorithm>
#include <sstream>
#include <string>

namespace pbf
{
namespace cuda
{
namespace
{

std::string number(double v)
{
  std::ostringstream out;
  out << v;
  return out.str();
}

// A device array that grows and never shrinks. Too little device memory is the input's fault
// (too fine a surface for this GPU): InvalidInput, naming what was asked.
class Scratch
{
public:
  Scratch() = default;
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  ~Scratch() { release(); }

  template <class T>
  T* as(std::size_t count, const char* what)
  {
    const std::size_t bytes = std::max<std::size_t>(count * sizeof(T), 256);
    if (bytes > bytes_)
    {
      release();
      const cudaError_t e = cudaMalloc(&p_, bytes);
      if (e == cudaErrorMemoryAllocation)
      {
        cudaGetLastError();
        p_ = nullptr;
        throw InvalidInput(std::string("Surface: ") + number(static_cast<double>(bytes)) +
          " bytes of GPU memory for the " + what +
          " are not free; coarsen SurfaceResolution or use fewer particles");
      }
      check(e, "cudaMalloc (surface)");
      bytes_ = bytes;
    }
    return static_cast<T*>(p_);
  }
  std::size_t bytes() const { return bytes_; }
  void release()
  {
    if (p_)
    {
      cudaFree(p_);
    }
    p_ = nullptr;
    bytes_ = 0;
  }

private:
  void* p_ = nullptr;
  std::size_t bytes_ = 0;
};

} // namespace
} // namespace cuda
} // namespace pbf
