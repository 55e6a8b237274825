// SubdomainStepper's exchanges with the other ranks: the cut, the migration of particles to the
// owners of their columns, the ghosts received, sorted with the owned particles and refreshed
// from their owners, and dropped again.
#include "SubdomainStepper.h"

#include "RankReductions.h"

#include <algorithm>
#include <chrono>
#include <type_traits>

namespace pbf::distributed
{

namespace
{

double millisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
    .count();
}

template <class Real>
void putVec(Bytes& b, const Vec3<Real>& v)
{
  put(b, v.x);
  put(b, v.y);
  put(b, v.z);
}

template <class Real>
Vec3<Real> takeVec(const Bytes& b, std::size_t& offset)
{
  Vec3<Real> v;
  v.x = take<Real>(b, offset);
  v.y = take<Real>(b, offset);
  v.z = take<Real>(b, offset);
  return v;
}

} // namespace

template <class Real>
void SubdomainStepper<Real>::cut()
{
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> mine(static_cast<std::size_t>(columns_.nx), 0.0);
  for (const Vec3<Real>& q : fluid_.x)
  {
    mine[static_cast<std::size_t>(column(q))] += 1.0;
  }
  std::vector<std::uint64_t> perColumn(mine.size(), 0);
  for (const std::vector<double>& r : allGather(communicator_, mine))
  {
    for (std::size_t c = 0; c < r.size(); ++c)
    {
      perColumn[c] += static_cast<std::uint64_t>(r[c]);
    }
  }
  const Slabs balanced = Slabs::balanced(perColumn, communicator_.size());
  exchange_.cutMoved = balanced.first != slabs_.first;
  slabs_ = balanced;
  exchange_.migrationMilliseconds += millisecondsSince(start);
  fluid_.p.resize(fluid_.x.size());
  migrate(false);
}

template <class Real>
void SubdomainStepper<Real>::migrate(bool byPrediction)
{
  const auto start = std::chrono::steady_clock::now();
  const int me = communicator_.rank();
  std::vector<Bytes> out(static_cast<std::size_t>(communicator_.size()));
  std::size_t kept = 0;
  const bool liquids = !fluid_.parameters.liquids.empty();
  for (std::size_t i = 0; i < fluid_.x.size(); ++i)
  {
    const int owner = slabs_.owner(column(byPrediction ? fluid_.p[i] : fluid_.x[i]));
    if (owner == me)
    {
      fluid_.x[kept] = fluid_.x[i];
      fluid_.p[kept] = fluid_.p[i];
      fluid_.v[kept] = fluid_.v[i];
      fluid_.id[kept] = fluid_.id[i];
      fluid_.density[kept] = fluid_.density[i];
      fluid_.lambda[kept] = fluid_.lambda[i];
      fluid_.pressure[kept] = fluid_.pressure[i];
      if (liquids)
      {
        fluid_.liquid[kept] = fluid_.liquid[i];
      }
      ++kept;
      continue;
    }
    Bytes& b = out[static_cast<std::size_t>(owner)];
    putVec(b, fluid_.x[i]);
    putVec(b, fluid_.p[i]);
    putVec(b, fluid_.v[i]);
    put(b, fluid_.id[i]);
    put(b, fluid_.density[i]);
    put(b, fluid_.lambda[i]);
    put(b, fluid_.pressure[i]);
    if (liquids)
    {
      put(b, fluid_.liquid[i]);
    }
  }
  fluid_.x.resize(kept);
  fluid_.p.resize(kept);
  fluid_.v.resize(kept);
  fluid_.id.resize(kept);
  fluid_.density.resize(kept);
  fluid_.lambda.resize(kept);
  fluid_.pressure.resize(kept);
  fluid_.liquid.resize(liquids ? kept : 0);
  const std::vector<Bytes> in = communicator_.exchange(out);
  out.clear();
  std::size_t arriving = 0;
  const std::size_t record = 3 * sizeof(Vec3<Real>) + sizeof(std::int64_t) + 3 * sizeof(Real) +
    (liquids ? sizeof(std::uint8_t) : 0);
  for (const Bytes& b : in)
  {
    arriving += b.size() / record;
  }
  roomFor(kept + arriving);
  for (const Bytes& b : in)
  {
    for (std::size_t offset = 0; offset < b.size();)
    {
      fluid_.x.push_back(takeVec<Real>(b, offset));
      fluid_.p.push_back(takeVec<Real>(b, offset));
      fluid_.v.push_back(takeVec<Real>(b, offset));
      fluid_.id.push_back(take<std::int64_t>(b, offset));
      fluid_.density.push_back(take<Real>(b, offset));
      fluid_.lambda.push_back(take<Real>(b, offset));
      fluid_.pressure.push_back(take<Real>(b, offset));
      if (liquids)
      {
        fluid_.liquid.push_back(take<std::uint8_t>(b, offset));
      }
      ++exchange_.migrated;
    }
  }
  exchange_.migrationMilliseconds += millisecondsSince(start);
}

template <class Real>
void SubdomainStepper<Real>::receiveGhosts()
{
  const auto start = std::chrono::steady_clock::now();
  const int me = communicator_.rank();
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  const std::size_t owned = fluid_.x.size();
  // Which owned particles each rank mirrors, by index before the sort (mapped after it).
  std::vector<std::vector<std::uint32_t>> sendOriginal(ranks);
  std::vector<Bytes> out(ranks);
  const bool liquids = !fluid_.parameters.liquids.empty();
  for (std::size_t i = 0; i < owned; ++i)
  {
    const int c = column(fluid_.p[i]);
    const int left = c > 0 ? slabs_.owner(c - 1) : me;
    const int right = c + 1 < slabs_.columns() ? slabs_.owner(c + 1) : me;
    for (int to : { left, right })
    {
      if (to == me || (to == right && right == left))
      {
        continue;
      }
      sendOriginal[static_cast<std::size_t>(to)].push_back(static_cast<std::uint32_t>(i));
      Bytes& b = out[static_cast<std::size_t>(to)];
      putVec(b, fluid_.p[i]);
      put(b, fluid_.id[i]);
      if (liquids)
      {
        put(b, fluid_.liquid[i]);
      }
    }
  }
  const std::vector<Bytes> in = communicator_.exchange(out);
  out.clear();
  std::size_t arriving = 0;
  const std::size_t record = sizeof(Vec3<Real>) + sizeof(std::int64_t) + (liquids ? sizeof(std::uint8_t) : 0);
  for (const Bytes& b : in)
  {
    arriving += b.size() / record;
  }
  roomFor(owned + arriving);
  std::vector<std::int32_t> from;
  from.reserve(capacity_);
  from.assign(owned, -1);
  for (std::size_t r = 0; r < ranks; ++r)
  {
    for (std::size_t offset = 0; offset < in[r].size();)
    {
      const Vec3<Real> q = takeVec<Real>(in[r], offset);
      fluid_.x.push_back(q);
      fluid_.p.push_back(q);
      fluid_.v.push_back(Vec3<Real>{ Real(0), Real(0), Real(0) });
      fluid_.id.push_back(take<std::int64_t>(in[r], offset));
      if (liquids)
      {
        fluid_.liquid.push_back(take<std::uint8_t>(in[r], offset));
      }
      from.push_back(static_cast<std::int32_t>(r));
    }
  }
  const std::size_t n = fluid_.x.size();
  exchange_.ghosts = n - owned;
  fluid_.density.resize(n);
  fluid_.lambda.resize(n);
  fluid_.pressure.resize(n);
  fluid_.scratch.resize(n);
  fluid_.omega.resize(n);
  fluid_.colour.resize(fluid_.coefficients.surfaceTension ? n : 0);
  fluid_.normal.resize(fluid_.coefficients.surfaceTension ? n : 0);
  fluid_.keys.resize(n);
  tag_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    tag_[i] = static_cast<std::uint32_t>(i);
  }
  // Kept for sortByCell, which maps both lists to sorted indices.
  for (std::size_t r = 0; r < ranks; ++r)
  {
    sendIndex_[r].assign(sendOriginal[r].begin(), sendOriginal[r].end()); // keeps the planned room
    ghostIndex_[r].clear();
  }
  ghostFrom_ = std::move(from);
  exchange_.ghostMilliseconds += millisecondsSince(start);
}

template <class Real>
void SubdomainStepper<Real>::sortByCell()
{
  const std::size_t n = fluid_.x.size();
  // The window: the columns of the particles sorted (owned and ghosts), so that the cells are
  // this rank's share of the domain's; a key is the domain's column offset, the same order.
  int lo = columns_.nx, hi = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const int c = column(fluid_.p[i]);
    lo = std::min(lo, c);
    hi = std::max(hi, c + 1);
  }
  fluid_.geometry.firstColumn = lo < hi ? lo : 0;
  fluid_.geometry.nx = lo < hi ? hi - lo : 1;
  roomForCells(fluid_.geometry.nx);
  // Serially over owned particles and ghosts, as before this rank knows which are which.
  fluid_.sortByCell(
    [n](auto&& f) {
      for (std::size_t i = 0; i < n; ++i)
      {
        f(static_cast<std::uint32_t>(i));
      }
    },
    [&](auto&& gather) {
      gather(tag_, gatherIndex_);
      gather(ghostFrom_, gatherFrom_);
    });
  // Sorted index of each pre-sort index; ghosts keep their arrival order per rank, which is the
  // order in which their owner packs their fields.
  std::vector<std::uint32_t>& sortedOf = gatherIndex_;
  sortedOf.resize(n);
  owned_.clear();
  for (std::size_t k = 0; k < n; ++k)
  {
    sortedOf[tag_[k]] = static_cast<std::uint32_t>(k);
  }
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::uint32_t k = sortedOf[i];
    if (ghostFrom_[k] >= 0)
    {
      ghostIndex_[static_cast<std::size_t>(ghostFrom_[k])].push_back(k);
    }
  }
  for (std::size_t k = 0; k < n; ++k)
  {
    if (ghostFrom_[k] < 0)
    {
      owned_.push_back(static_cast<std::uint32_t>(k));
    }
  }
  for (auto& list : sendIndex_)
  {
    for (std::uint32_t& i : list)
    {
      i = sortedOf[i];
    }
  }
}

template <class Real>
template <class Field>
void SubdomainStepper<Real>::refreshGhosts(Field field)
{
  const auto start = std::chrono::steady_clock::now();
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  std::vector<Bytes> out(ranks);
  for (std::size_t r = 0; r < ranks; ++r)
  {
    for (std::uint32_t i : sendIndex_[r])
    {
      put(out[r], field(i));
    }
  }
  const std::vector<Bytes> in = communicator_.exchange(out);
  for (std::size_t r = 0; r < ranks; ++r)
  {
    std::size_t offset = 0;
    for (std::uint32_t i : ghostIndex_[r])
    {
      field(i) = take<std::remove_reference_t<decltype(field(i))>>(in[r], offset);
    }
  }
  exchange_.ghostMilliseconds += millisecondsSince(start);
}

template <class Real>
void SubdomainStepper<Real>::dropGhosts()
{
  const std::size_t owned = owned_.size();
  auto keep = [&](auto& array) {
    for (std::size_t k = 0; k < owned; ++k)
    {
      array[k] = array[owned_[k]]; // owned_ is increasing: never overwrites one still to read
    }
    array.resize(owned);
  };
  keep(fluid_.x);
  keep(fluid_.p);
  keep(fluid_.v);
  keep(fluid_.id);
  keep(fluid_.density);
  keep(fluid_.lambda);
  keep(fluid_.pressure);
  if (!fluid_.liquid.empty())
  {
    keep(fluid_.liquid);
  }
  ghostFrom_.assign(owned, -1);
}

template <class Real>
void SubdomainStepper<Real>::refresh(HostField field)
{
  switch (field)
  {
    case HostField::DensityAndLambda:
      refreshGhosts([&](std::uint32_t i) -> Real& { return fluid_.density[i]; });
      refreshGhosts([&](std::uint32_t i) -> Real& { return fluid_.lambda[i]; });
      break;
    case HostField::Predicted:
      refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.p[i]; });
      break;
    case HostField::Velocity:
      refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.v[i]; });
      break;
    case HostField::Vorticity:
      refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.omega[i]; });
      if (fluid_.parameters.xsphHyperViscosity > 0)
      {
        // XSPH's sum (HostFluid::view puts it in scratch), which the bi-Laplacian smooths.
        refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.scratch[i]; });
      }
      if (!fluid_.colour.empty())
      {
        // grad c, whose normals the confinement's surface tension reads (SurfaceTension.h).
        refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.colour[i]; });
      }
      break;
    case HostField::Normal:
      refreshGhosts([&](std::uint32_t i) -> Vec3<Real>& { return fluid_.normal[i]; });
      break;
  }
}

// The members defined here, for both precisions (SubdomainStepper.cpp instantiates the class).
template void SubdomainStepper<float>::cut();
template void SubdomainStepper<double>::cut();
template void SubdomainStepper<float>::migrate(bool);
template void SubdomainStepper<double>::migrate(bool);
template void SubdomainStepper<float>::receiveGhosts();
template void SubdomainStepper<double>::receiveGhosts();
template void SubdomainStepper<float>::sortByCell();
template void SubdomainStepper<double>::sortByCell();
template void SubdomainStepper<float>::dropGhosts();
template void SubdomainStepper<double>::dropGhosts();
template void SubdomainStepper<float>::refresh(HostField);
template void SubdomainStepper<double>::refresh(HostField);

} // namespace pbf::distributed
