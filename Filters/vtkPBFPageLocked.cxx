#include "vtkPBFPageLocked.h"

#ifdef PBF_WITH_CUDA
#include <cuda_runtime.h>
#endif

#include <map>
#include <mutex>
#include <unordered_map>

namespace
{

// In use at most: about 25 frames of a million single-precision particles (40 bytes each).
constexpr std::size_t Limit = std::size_t(1) << 30;
// Kept for reuse at most: a few frames' worth; more is unpinned.
constexpr std::size_t PoolLimit = std::size_t(512) << 20;

struct Pool
{
  std::mutex Mutex;
  std::multimap<std::size_t, void*> Free;      // by size
  std::unordered_map<void*, std::size_t> Used; // handed out
  std::size_t UsedBytes = 0;
  std::size_t FreeBytes = 0;
};

// Never destroyed: VTK arrays may release their memory during static destruction.
Pool& ThePool()
{
  static Pool* pool = new Pool;
  return *pool;
}

} // namespace

namespace vtkPBFPageLocked
{

bool Available()
{
#ifdef PBF_WITH_CUDA
  return true;
#else
  return false;
#endif
}

void* Allocate(std::size_t size)
{
#ifdef PBF_WITH_CUDA
  if (size == 0)
  {
    return nullptr;
  }
  Pool& pool = ThePool();
  std::lock_guard<std::mutex> lock(pool.Mutex);
  if (pool.UsedBytes + size > Limit)
  {
    return nullptr;
  }
  void* memory = nullptr;
  std::size_t held = size;
  // A released buffer of this size, or one at most a quarter larger.
  auto it = pool.Free.lower_bound(size);
  if (it != pool.Free.end() && it->first <= size + size / 4)
  {
    held = it->first;
    memory = it->second;
    pool.FreeBytes -= held;
    pool.Free.erase(it);
  }
  else if (cudaHostAlloc(&memory, size, cudaHostAllocDefault) != cudaSuccess)
  {
    cudaGetLastError(); // clear it: the caller falls back to ordinary memory
    return nullptr;
  }
  pool.Used.emplace(memory, held);
  pool.UsedBytes += held;
  return memory;
#else
  (void)size;
  return nullptr;
#endif
}

void Release(void* memory)
{
#ifdef PBF_WITH_CUDA
  if (!memory)
  {
    return;
  }
  Pool& pool = ThePool();
  std::lock_guard<std::mutex> lock(pool.Mutex);
  auto it = pool.Used.find(memory);
  if (it == pool.Used.end())
  {
    return;
  }
  const std::size_t size = it->second;
  pool.Used.erase(it);
  pool.UsedBytes -= size;
  if (pool.FreeBytes + size > PoolLimit)
  {
    cudaFreeHost(memory);
    return;
  }
  pool.Free.emplace(size, memory);
  pool.FreeBytes += size;
#else
  (void)memory;
#endif
}

std::size_t BytesInUse()
{
  Pool& pool = ThePool();
  std::lock_guard<std::mutex> lock(pool.Mutex);
  return pool.UsedBytes;
}

std::size_t BytesPooled()
{
  Pool& pool = ThePool();
  std::lock_guard<std::mutex> lock(pool.Mutex);
  return pool.FreeBytes;
}

} // namespace vtkPBFPageLocked
