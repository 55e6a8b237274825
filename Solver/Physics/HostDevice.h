// PBF_HD marks functions that the CPU backends and the CUDA kernels share, so that the PBF
// equations exist once and the backends cannot drift apart.
#pragma once

#if defined(__CUDACC__)
#define PBF_HD __host__ __device__
#define PBF_INLINE __forceinline__
#else
#define PBF_HD
#define PBF_INLINE inline
#endif
