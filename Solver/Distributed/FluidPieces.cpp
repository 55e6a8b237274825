#include "FluidPieces.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace pbf::distributed
{
namespace
{

// A particle's record in the exchange: x, v, id, liquid.
constexpr std::size_t kRecord = 6 * sizeof(double) + sizeof(std::int64_t) + sizeof(std::uint8_t);

} // namespace

FluidPieces::FluidPieces(const ParticleBatch& piece, Communicator& communicator,
  std::size_t perMessage)
  : piece_(piece)
  , communicator_(communicator)
  , perMessage_(perMessage > 0 ? perMessage : 1)
{
  // A piece with no points carries no liquid array: the others say whether the fluid has one.
  for (const std::vector<double>& part : allGather(communicator_, { piece_.liquid.empty() ? 0.0 : 1.0 }))
  {
    liquids_ = liquids_ || part[0] != 0.0;
  }
}

void FluidPieces::forEachPosition(const std::function<void(const Vec3d&)>& visit) const
{
  for (const Vec3d& x : piece_.position)
  {
    visit(x);
  }
}

void FluidPieces::forEachWhere(const Keep& keep, const Visit& visit) const
{
  for (std::size_t i = 0; i < piece_.position.size(); ++i)
  {
    if (keep(piece_.position[i]))
    {
      visit(piece_.position[i], piece_.velocity[i], piece_.id[i],
        piece_.liquid.empty() ? std::uint8_t(0) : piece_.liquid[i]);
    }
  }
}

std::vector<std::vector<double>> FluidPieces::allParts(const std::vector<double>& mine) const
{
  return allGather(communicator_, mine);
}

void FluidPieces::forEachOwned(const Owner& owner, int rank, const Visit& visit) const
{
  if (rank != communicator_.rank())
  {
    throw std::logic_error("FluidPieces::forEachOwned: rank " + std::to_string(rank) +
      " asked on rank " + std::to_string(communicator_.rank()) + ": a rank receives its own slab");
  }
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  // Each destination's particles, in the piece's order (a piece holds fewer than 2^32: checkBatch).
  std::vector<std::vector<std::uint32_t>> to(ranks);
  for (std::size_t i = 0; i < piece_.position.size(); ++i)
  {
    const int r = owner(piece_.position[i]);
    if (r < 0 || static_cast<std::size_t>(r) >= ranks)
    {
      throw std::logic_error("FluidPieces::forEachOwned: owner " + std::to_string(r) + " of " +
        std::to_string(ranks) + " ranks");
    }
    to[static_cast<std::size_t>(r)].push_back(static_cast<std::uint32_t>(i));
  }
  std::size_t most = 0;
  for (const std::vector<std::uint32_t>& list : to)
  {
    most = std::max(most, list.size());
  }
  std::size_t rounds = 0;
  const double mine = static_cast<double>((most + perMessage_ - 1) / perMessage_);
  for (const std::vector<double>& part : allGather(communicator_, { mine }))
  {
    rounds = std::max(rounds, static_cast<std::size_t>(part[0]));
  }
  std::vector<Bytes> incoming(ranks);
  for (std::size_t round = 0; round < rounds; ++round)
  {
    std::vector<Bytes> outgoing(ranks);
    for (std::size_t r = 0; r < ranks; ++r)
    {
      const std::size_t from = std::min(to[r].size(), round * perMessage_);
      const std::size_t end = std::min(to[r].size(), from + perMessage_);
      Bytes& out = outgoing[r];
      out.reserve((end - from) * kRecord);
      for (std::size_t k = from; k < end; ++k)
      {
        const std::size_t i = to[r][k];
        put(out, piece_.position[i]);
        put(out, piece_.velocity[i]);
        put(out, piece_.id[i]);
        put(out, piece_.liquid.empty() ? std::uint8_t(0) : piece_.liquid[i]);
      }
    }
    outgoing = communicator_.exchange(outgoing);
    for (std::size_t r = 0; r < ranks; ++r)
    {
      // One round (the usual case) keeps what arrived as it is: no second copy of the slab.
      if (incoming[r].empty())
      {
        incoming[r].swap(outgoing[r]);
      }
      else
      {
        incoming[r].insert(incoming[r].end(), outgoing[r].begin(), outgoing[r].end());
      }
    }
  }
  for (const Bytes& from : incoming)
  {
    if (from.size() % kRecord != 0)
    {
      throw std::runtime_error("FluidPieces: a message of " + std::to_string(from.size()) +
        " bytes is not whole particles of " + std::to_string(kRecord));
    }
    for (std::size_t at = 0; at < from.size();)
    {
      const auto x = take<Vec3d>(from, at);
      const auto v = take<Vec3d>(from, at);
      const auto id = take<std::int64_t>(from, at);
      const auto liquid = take<std::uint8_t>(from, at);
      visit(x, v, id, liquid);
    }
  }
}

} // namespace pbf::distributed
