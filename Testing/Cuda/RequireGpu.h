// The GPU tests' guard: without a usable CUDA device a test reports SKIPPED (CTest counts it as
// skipped, not passed), with the reason. Where a GPU must be (PBF_GPU_REQUIRED=1, which
// Utilities/gpu/run.sh sets on the GPU machine) it fails instead: a regression in device
// detection would otherwise turn every GPU test into a skip and the GPU run would stay green.
#pragma once

#include "Backends.h"
#include "Stepper.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string>

namespace pbf::test
{
inline bool gpuRequired()
{
  const char* required = std::getenv("PBF_GPU_REQUIRED");
  return required && std::strcmp(required, "1") == 0;
}
} // namespace pbf::test

#define PBF_REQUIRE_GPU()                                                                          \
  do                                                                                               \
  {                                                                                                \
    std::string why;                                                                               \
    if (!pbf::cudaAvailable(&why))                                                                 \
    {                                                                                              \
      if (pbf::test::gpuRequired())                                                                \
      {                                                                                            \
        GTEST_FAIL() << "no usable CUDA device, and PBF_GPU_REQUIRED=1: " << why;                  \
      }                                                                                            \
      GTEST_SKIP() << "no usable CUDA device: " << why;                                            \
    }                                                                                              \
  } while (0)
