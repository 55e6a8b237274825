#include "CellSort.h"

#include <algorithm>

namespace pbf
{

void countingSortByCell(const std::vector<CellKey>& keys, std::vector<std::uint32_t>& cellOffsets,
  std::vector<std::uint32_t>& order, std::vector<std::uint32_t>& cursor)
{
  const std::size_t n = keys.size();
  std::fill(cellOffsets.begin(), cellOffsets.end(), 0u);
  for (std::size_t i = 0; i < n; ++i)
  {
    ++cellOffsets[keys[i] + 1];
  }
  for (std::size_t c = 1; c < cellOffsets.size(); ++c)
  {
    cellOffsets[c] += cellOffsets[c - 1];
  }
  order.resize(n);
  cursor.assign(cellOffsets.begin(), cellOffsets.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
  {
    order[cursor[keys[i]]++] = static_cast<std::uint32_t>(i);
  }
}

} // namespace pbf
