#include "SurfaceShare.h"

#include <cstring>

namespace pbf
{

SurfaceShare slabShare(const distributed::Slabs& slabs, int rank, const Parameters& p)
{
  const double h = p.smoothingLength();
  const auto r = static_cast<std::size_t>(rank);
  SurfaceShare share;
  if (rank > 0)
  {
    share.xMin = p.domain.min.x + slabs.first[r] * h;
  }
  if (rank + 1 < slabs.ranks())
  {
    share.xMax = p.domain.min.x + slabs.first[r + 1] * h;
  }
  return share;
}

template <class Real>
SurfaceMesh extractSurfaceShare(distributed::Communicator& communicator, const distributed::Slabs& slabs,
  const Vec3<Real>* x, const Vec3<Real>* v, const Real* rho, std::size_t n,
  const Parameters& p, const SurfaceOptions& options, bool parallel, const SurfaceSolids& solids)
{
  options.validate();
  const int ranks = communicator.size();
  const int me = communicator.rank();
  const double reach = surfaceGhostReach(p, options);
  // To each other rank, the particles within reach of its slab: position, velocity, density.
  struct Record
  {
    Vec3<Real> x, v;
    Real rho;
  };
  std::vector<distributed::Bytes> outgoing(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r)
  {
    if (r == me)
    {
      continue;
    }
    const SurfaceShare theirs = slabShare(slabs, r, p);
    distributed::Bytes& out = outgoing[static_cast<std::size_t>(r)];
    for (std::size_t i = 0; i < n; ++i)
    {
      if (x[i].x >= theirs.xMin - reach && x[i].x < theirs.xMax + reach)
      {
        const Record record{ x[i], v ? v[i] : Vec3<Real>{ 0, 0, 0 }, rho ? rho[i] : Real(0) };
        const std::size_t at = out.size();
        out.resize(at + sizeof record);
        std::memcpy(out.data() + at, &record, sizeof record);
      }
    }
  }
  const std::vector<distributed::Bytes> incoming = communicator.exchange(outgoing);
  std::vector<Vec3<Real>> allX(x, x + n), allV;
  std::vector<Real> densities;
  if (v)
  {
    allV.assign(v, v + n);
  }
  if (rho)
  {
    densities.assign(rho, rho + n);
  }
  for (const distributed::Bytes& in : incoming)
  {
    for (std::size_t at = 0; at + sizeof(Record) <= in.size(); at += sizeof(Record))
    {
      Record record;
      std::memcpy(&record, in.data() + at, sizeof record);
      allX.push_back(record.x);
      if (v)
      {
        allV.push_back(record.v);
      }
      if (rho)
      {
        densities.push_back(record.rho);
      }
    }
  }
  return extractSurface<Real>(allX.data(), v ? allV.data() : nullptr,
    rho ? densities.data() : nullptr, allX.size(), p, options, parallel, slabShare(slabs, me, p),
    solids);
}

template SurfaceMesh extractSurfaceShare<float>(distributed::Communicator&, const distributed::Slabs&,
  const Vec3<float>*, const Vec3<float>*, const float*, std::size_t, const Parameters&,
  const SurfaceOptions&, bool, const SurfaceSolids&);
template SurfaceMesh extractSurfaceShare<double>(distributed::Communicator&, const distributed::Slabs&,
  const Vec3<double>*, const Vec3<double>*, const double*, std::size_t, const Parameters&,
  const SurfaceOptions&, bool, const SurfaceSolids&);

} // namespace pbf
