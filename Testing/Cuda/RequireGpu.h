// The GPU tests' guard: without a usable CUDA device a test reports SKIPPED (CTest counts it as
// skipped, not passed), with the reason.
#pragma once

#include "Stepper.h"

#include <gtest/gtest.h>

#include <string>

#define PBF_REQUIRE_GPU()                                                                          \
  do                                                                                               \
  {                                                                                                \
    std::string why;                                                                               \
    if (!pbf::cudaAvailable(&why))                                                                 \
    {                                                                                              \
      GTEST_SKIP() << "no usable CUDA device: " << why;                                            \
    }                                                                                              \
  } while (0)
