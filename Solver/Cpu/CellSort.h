// The CPU grid build: a stable counting sort of particles by cell key. Stability makes the
// permutation unique, so every CPU backend (and a stable radix sort on the GPU) orders particles
// the same way.
#pragma once

#include "Grid.h"

#include <cstdint>
#include <vector>

namespace pbf
{

// keys[i] is particle i's cell. On return cellOffsets (cellCount + 1 entries) holds each cell's
// sorted index range and order[k] the particle that goes to sorted index k. cursor is scratch,
// passed in so that stepping does not allocate.
void countingSortByCell(const std::vector<CellKey>& keys, std::vector<std::uint32_t>& cellOffsets,
  std::vector<std::uint32_t>& order, std::vector<std::uint32_t>& cursor);

} // namespace pbf
