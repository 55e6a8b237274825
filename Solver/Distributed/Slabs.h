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
    std::vector<double> shares(static_cast<std::size_t>(ranks > 0 ? ranks : 0), 1.0);
    return cut(perColumn, ranks, shares);
  }

  // As balanced(), but counting each of a rank's ghosts (the particles of the column just beyond
  // each of its borders) as borderWeight particles more, so that ranks with two borders take
  // fewer particles than the two end ranks. On GPUs a border costs far more than its particles:
  // its pass is a launch of its own, packed, copied and waited for in every exchange round
  // (Testing/Benchmarks/DISTRIBUTED.md measures it). A function of the column counts alone, as
  // balanced() is; borderWeight 0 gives balanced()'s cut.
  static Slabs balancedWithBorders(
    const std::vector<std::uint64_t>& perColumn, int ranks, double borderWeight)
  {
    const Slabs even = balanced(perColumn, ranks);
    if (borderWeight <= 0 || ranks < 3)
    {
      return even; // with two ranks each has one border
    }
    // The ghosts of a border: the mean over the even cut's borders of the column beyond it.
    // Taking the mean rather than each border's own column keeps ranks with as many borders on
    // equal terms (two ranks get the even cut), so the cut does not follow every fluctuation of
    // the columns beside it.
    const int columns = even.columns();
    double total = 0, ghostsAll = 0;
    for (int c = 0; c < columns; ++c)
    {
      total += static_cast<double>(perColumn[static_cast<std::size_t>(c)]);
    }
    for (int r = 1; r < ranks; ++r)
    {
      const auto at = static_cast<std::size_t>(even.first[static_cast<std::size_t>(r)]);
      ghostsAll += static_cast<double>(perColumn[at - 1] + perColumn[at]);
    }
    const double perBorder = ghostsAll / (2.0 * (ranks - 1));
    // Equal load n_r + w g_r on every rank: n_r = (total + w sum g) / ranks - w g_r, at least 0.
    const double load = (total + borderWeight * ghostsAll) / ranks;
    std::vector<double> shares(static_cast<std::size_t>(ranks));
    double sum = 0;
    for (int r = 0; r < ranks; ++r)
    {
      const int borders = (r > 0 ? 1 : 0) + (r + 1 < ranks ? 1 : 0);
      const double n = load - borderWeight * perBorder * borders;
      shares[static_cast<std::size_t>(r)] = n > 0 ? n : 0.0;
      sum += shares[static_cast<std::size_t>(r)];
    }
    if (!(sum > 0))
    {
      return even;
    }
    return cut(perColumn, ranks, shares);
  }

private:
  // Rank r gets about shares[r] / sum(shares) of the particles, each rank at least one column.
  static Slabs cut(
    const std::vector<std::uint64_t>& perColumn, int ranks, const std::vector<double>& shares)
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
    double shareSum = 0;
    for (double w : shares)
    {
      shareSum += w;
    }
    Slabs s;
    s.first.push_back(0);
    std::uint64_t cumulative = 0;
    double shareBefore = 0;
    int column = 0;
    for (int r = 1; r < ranks; ++r)
    {
      // Cut where the running count comes nearest to the shares of ranks 0..r-1, leaving at least
      // one column to this rank and to each rank still to come.
      shareBefore += shares[static_cast<std::size_t>(r) - 1];
      const double target = static_cast<double>(total) * shareBefore / shareSum;
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
