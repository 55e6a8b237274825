// PBF_HD marks functions that the CPU backends and the CUDA kernels share, so that the PBF
// equations exist once and the backends cannot drift apart.
#pragma once

// PBF_NOINLINE keeps a rarely taken path out of its callers, so that its registers do not count
// against every kernel that inlines them.
#if defined(__CUDACC__)
#define PBF_HD __host__ __device__
#define PBF_INLINE __forceinline__
#define PBF_NOINLINE __noinline__
#else
#define PBF_HD
#define PBF_INLINE inline
#define PBF_NOINLINE __attribute__((noinline))
#endif
