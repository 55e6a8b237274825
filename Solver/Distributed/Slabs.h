// The decomposition: slabs of whole grid columns along x, one per rank. Cutting on cell borders
// makes a rank's ghosts exactly the particles of the one column beyond each of its borders (the
// grid's neighbour search reaches one cell), so every owned particle sees the same neighbour
// candidates as in a single-rank run.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbf::distributed
{

struct Slabs
{
  // Rank r owns the columns [first[r], first[r + 1]); first.front() = 0, first.back() = columns.
  std::vector<int> first;

  int ranks() const { return static_cast<int>(first.size()) - 1; }
  int columns() const { return first.back(); }

  int owner(int column) const
  {
    int r = 0;
    while (r + 1 < ranks() && column >= first[static_cast<std::size_t>(r) + 1])
    {
      ++r;
    }
    return r;
  }

  // Cuts so that each rank holds about the same number of particles (perColumn: the particle
  // count of each column, summed over all ranks), each at least one column wide.
  static Slabs balanced(const std::vector<std::uint64_t>& perColumn, int ranks)
  {
    const int columns = static_cast<int>(perColumn.size());
    if (ranks < 1 || columns < ranks)
    {
      throw std::invalid_argument("slabs: " + std::to_string(ranks) + " ranks for " +
        std::to_string(columns) + " grid columns along x: each rank needs at least one column " +
        "(use fewer ranks or a smaller smoothing length)");
    }
    std::uint64_t total = 0;
    for (std::uint64_t n : perColumn)
    {
      total += n;
    }
    Slabs s;
    s.first.push_back(0);
    std::uint64_t cumulative = 0;
    int column = 0;
    for (int r = 1; r < ranks; ++r)
    {
      // Cut where the running count comes nearest to r/ranks of the total, leaving at least one
      // column to this rank and to each rank still to come.
      const double target = static_cast<double>(total) * r / ranks;
      while (column < columns - (ranks - r))
      {
        const double before = static_cast<double>(cumulative);
        const double after = before + static_cast<double>(perColumn[static_cast<std::size_t>(column)]);
        if (column >= s.first.back() + 1 && (before >= target || target - before <= after - target))
        {
          break;
        }
        cumulative += perColumn[static_cast<std::size_t>(column)];
        ++column;
      }
      s.first.push_back(column);
    }
    s.first.push_back(columns);
    return s;
  }
};

} // namespace pbf::distributed
