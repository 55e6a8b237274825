// The decomposition: slabs of whole grid columns along x, one per rank. Cutting on cell borders
// makes a rank's ghosts exactly the particles of the one column beyond each of its borders (the
// grid's neighbour search reaches one cell), so every owned particle sees the same neighbour
// candidates as in a single-rank run.
#pragma once

#include <cstddef>
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

  // The particles rank r's arrays first make room for, from the fluid's count per column: its
  // share, its ghosts (its neighbours' border columns), the migration's swing (a balanced cut
  // moves by whole columns: two of the largest) and 1 % more. The first evaluation and the first
  // steps then grow nothing, and the arrays hold 1.01-1.02 particles a particle at scale.
  std::size_t plannedCapacity(const std::vector<std::uint64_t>& perColumn, int r) const
  {
    const auto from = static_cast<std::size_t>(first[static_cast<std::size_t>(r)]);
    const auto to = static_cast<std::size_t>(first[static_cast<std::size_t>(r) + 1]);
    std::uint64_t owned = 0, largest = 0, ghosts = 0;
    for (std::size_t c = 0; c < perColumn.size(); ++c)
    {
      owned += c >= from && c < to ? perColumn[c] : 0;
      largest = largest > perColumn[c] ? largest : perColumn[c];
    }
    ghosts += r > 0 && from > 0 ? perColumn[from - 1] : 0;
    ghosts += r < ranks() - 1 && to < perColumn.size() ? perColumn[to] : 0;
    return static_cast<std::size_t>(owned + ghosts + 2 * largest + owned / 100);
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
