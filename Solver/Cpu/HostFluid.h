// The particles and per-step constants of a stepper that keeps its particles in host arrays: the
// serial and OpenMP stepper (CpuStepper) and one rank's CPU sub-domain (SubdomainStepper, which
// appends its ghosts to the same arrays during a step). The two differ in which particles they
// run the stages over and in what they exchange; what the particles are, how the step's constants
// follow from the parameters and dt, and how the stages of Equations.h see the arrays is here.
#pragma once

#include "CellSort.h"
#include "Equations.h"
#include "Boundary.h"
#include "HostParticles.h"
#include "SignedDistance.h"
#include "Stepper.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace pbf
{

template <class Real>
struct HostFluid
{
  // Validates the parameters and derives the constants; dt = parameters.timeStep.
  explicit HostFluid(const Parameters& p)
    : parameters(p)
  {
    parameters.validate();
    coefficients = Coefficients<Real>::make(parameters);
    lattice = calibrateLattice(parameters);
    setTimeStep(parameters.timeStep);
    geometry = makeGridGeometry<Real>(parameters.domain, parameters.smoothingLength());
  }

  void setTimeStep(double step, double pressureElapsed = 0)
  {
    checkTimeStep(step);
    dt = step;
    time = StepTime<Real>::make(parameters, lattice, step, pressureElapsed);
  }

  // The arrays as the stages see them; `tensile`: this projection adds s_corr.
  FluidView<Real> view(bool tensile = false)
  {
    FluidView<Real> f{};
    f.x = x.data();
    f.p = p.data();
    f.v = v.data();
    f.density = density.data();
    f.lambda = lambda.data();
    f.pressure = pressure.data();
    f.liquid = liquid.empty() ? nullptr : liquid.data();
    f.scratch = scratch.data();
    f.omega = omega.data();
    f.colour = colour.empty() ? nullptr : colour.data();
    f.normal = normal.empty() ? nullptr : normal.data();
    // XSPH's sum goes where delta p was: the solve is over when it is written.
    f.smoothing = scratch.data();
    f.grid = GridView<Real>{ geometry, cellOffsets.data(), keys.data() };
    f.c = coefficients;
    f.time = &time;
    f.tensile = tensile;
    f.obstacles = obstacleViews.data();
    f.obstacleCount = static_cast<int>(obstacleViews.size());
    f.boundary = boundary;
    return f;
  }

  // The solids and the table of their sums (Boundary.h), in this precision, placed at `poses`.
  void setObstacles(const std::vector<DistanceGrid>& solids, const std::vector<SolidPose>& poses)
  {
    checkPoseCount(poses.size(), solids.size());
    obstacles = solids;
    obstacleViews.clear();
    for (const DistanceGrid& g : obstacles)
    {
      obstacleViews.push_back(g.view<Real>(g.phi.data(), g.shapeNodes(), g.normalNodes()));
    }
    const BoundaryTableData table = makeBoundaryTable(parameters);
    boundaryValues = table.packed<Real>();
    boundary = table.view(boundaryValues.data());
    setPoses(poses);
  }

  // Where the solids are from now on (SolidMotion.h); none: as sampled.
  void setPoses(const std::vector<SolidPose>& poses)
  {
    checkPoseCount(poses.size(), obstacles.size());
    for (std::size_t k = 0; k < poses.size(); ++k)
    {
      obstacleViews[k] = placed(obstacleViews[k], poses[k]);
    }
  }

  // Sorts the particles by the cell of p (Green 2008): keys, a counting sort (O(N + cells),
  // serial), then x, p, v, id, liquid, pressure (a mean over the frame's steps so far) and keys
  // gathered in the new order. forEach(f) runs f(i) for every
  // particle, in parallel or not; gatherMore(gather) gathers a stepper's own arrays the same way
  // (gather(array, scratch)).
  template <class ForEach, class GatherMore>
  void sortByCell(ForEach&& forEach, GatherMore&& gatherMore)
  {
    const std::size_t n = x.size();
    forEach([&](std::uint32_t i) { keys[i] = geometry.keyOf(p[i]); });
    // The grid's cells (a rank's window of the domain's: GridGeometry::firstColumn), made at the
    // first sort and kept while the window does not grow.
    cellOffsets.resize(std::size_t(geometry.cellCount()) + 1);
    countingSortByCell(keys, cellOffsets, order, cursor);
    // Into scratch kept from step to step: nothing is allocated once the arrays have their size.
    auto gather = [&](auto& array, auto& scratch) {
      scratch.resize(n);
      forEach([&](std::uint32_t k) { scratch[k] = array[order[k]]; });
      array.swap(scratch);
    };
    gather(x, gatherVec);
    gather(p, gatherVec);
    gather(v, gatherVec);
    gather(id, gatherId);
    if (!liquid.empty())
    {
      gather(liquid, gatherLiquid);
    }
    gather(pressure, gatherReal);
    gather(keys, gatherKey);
    gatherMore(gather);
  }

  HostParticles<Real> particles() { return { x, v, density, lambda, pressure, id, liquid }; }
  ConstHostParticles<Real> particles() const
  {
    return { x, v, density, lambda, pressure, id, liquid };
  }

  // Appends a batch's state (checkBatch first): its liquids, or liquid 0 where it carries none,
  // where the scene names liquids.
  void appendState(const ParticleBatch& batch)
  {
    for (std::size_t i = 0; i < batch.position.size(); ++i)
    {
      x.push_back(Vec3<Real>::from(batch.position[i]));
      v.push_back(Vec3<Real>::from(batch.velocity[i]));
      id.push_back(batch.id[i]);
    }
    if (!parameters.liquids.empty())
    {
      if (batch.liquid.empty())
      {
        liquid.resize(liquid.size() + batch.position.size(), 0);
      }
      else
      {
        liquid.insert(liquid.end(), batch.liquid.begin(), batch.liquid.end());
      }
    }
  }

  // Room for n particles in every per-particle array, so that none reallocates below n (the
  // sort's gathers swap buffers of one capacity); the liquids' and the tension's arrays only
  // where the scene uses them.
  void reserveParticles(std::size_t n)
  {
    for (auto* a : { &x, &p, &v, &scratch, &omega, &gatherVec })
    {
      a->reserve(n);
    }
    if (coefficients.surfaceTension)
    {
      colour.reserve(n);
      normal.reserve(n);
    }
    for (auto* a : { &density, &lambda, &pressure, &gatherReal })
    {
      a->reserve(n);
    }
    id.reserve(n);
    gatherId.reserve(n);
    if (!parameters.liquids.empty())
    {
      liquid.reserve(n);
      gatherLiquid.reserve(n);
    }
    keys.reserve(n);
    gatherKey.reserve(n);
    order.reserve(n);
  }

  // The bytes a particle takes in those arrays.
  std::size_t bytesPerParticle() const
  {
    const std::size_t vectors = 6 + (coefficients.surfaceTension ? 2 : 0);
    const std::size_t liquids = parameters.liquids.empty() ? 0 : 2;
    return vectors * sizeof(Vec3<Real>) + 4 * sizeof(Real) + 2 * sizeof(std::int64_t) +
      liquids * sizeof(std::uint8_t) + 2 * sizeof(CellKey) + sizeof(std::uint32_t);
  }

  // The bytes the arrays hold (their capacities), the grid's cell offsets included.
  std::size_t heldBytes() const
  {
    auto bytes = [](const auto& a) { return a.capacity() * sizeof(a[0]); };
    std::size_t sum = bytes(cellOffsets) + bytes(cursor) + bytes(order);
    for (const auto* a : { &x, &p, &v, &scratch, &omega, &gatherVec, &colour, &normal })
    {
      sum += bytes(*a);
    }
    for (const auto* a : { &density, &lambda, &pressure, &gatherReal })
    {
      sum += bytes(*a);
    }
    return sum + bytes(id) + bytes(gatherId) + bytes(liquid) + bytes(gatherLiquid) + bytes(keys) +
      bytes(gatherKey);
  }

  // The work arrays that follow the particle count (x, v and id are the state).
  void resizeWork(std::size_t n)
  {
    p.resize(n);
    scratch.resize(n);
    omega.resize(n);
    colour.resize(coefficients.surfaceTension ? n : 0);
    normal.resize(coefficients.surfaceTension ? n : 0);
    density.resize(n);
    lambda.resize(n);
    pressure.resize(n);
    keys.resize(n);
  }

  static Precision precision()
  {
    return sizeof(Real) == sizeof(float) ? Precision::Single : Precision::Double;
  }

  Parameters parameters;
  Coefficients<Real> coefficients;
  LatticeCalibration lattice;
  double dt = 0;
  StepTime<Real> time{};
  GridGeometry<Real> geometry;

  std::vector<Vec3<Real>> x, p, v, scratch, omega;
  // grad c per particle, for surface tension (FluidView::colour); empty without it.
  std::vector<Vec3<Real>> colour;
  std::vector<Vec3<Real>> normal; // grad c smoothed (FluidView::normal); empty without it
  std::vector<Real> density, lambda, pressure;
  std::vector<std::int64_t> id;
  // Each particle's liquid (Parameters::liquids); empty where the scene names none.
  std::vector<std::uint8_t> liquid;
  std::vector<CellKey> keys;
  std::vector<std::uint32_t> cellOffsets, order, cursor;
  // Gather targets of the cell sort, kept to avoid allocating every step.
  std::vector<Vec3<Real>> gatherVec;
  std::vector<Real> gatherReal;
  std::vector<std::int64_t> gatherId;
  std::vector<std::uint8_t> gatherLiquid;
  std::vector<CellKey> gatherKey;

  std::vector<DistanceGrid> obstacles;
  std::vector<DistanceGridView<Real>> obstacleViews;
  std::vector<Real> boundaryValues;
  BoundaryTable<Real> boundary{};
};

// stage(b, at(k)) for k in [0, n), b = k / block: the blocks in parallel (OpenMP, when
// `parallel`), each block's particles in order, so that sums kept per block and then added in
// block order have the same bits whatever the number of threads.
template <class At, class Stage>
void forEachInBlocks(bool parallel, std::size_t n, std::size_t block, At&& at, Stage&& stage)
{
  const auto blocks = static_cast<std::int64_t>((n + block - 1) / block);
#pragma omp parallel for schedule(static) if (parallel)
  for (std::int64_t b = 0; b < blocks; ++b)
  {
    const std::size_t end = std::min(n, static_cast<std::size_t>(b + 1) * block);
    for (std::size_t k = static_cast<std::size_t>(b) * block; k < end; ++k)
    {
      stage(static_cast<std::size_t>(b), at(k));
    }
  }
}

// The fields a stepper that does not own every particle it reads (a sub-domain, whose ghosts are
// owned by its neighbours) refreshes between the stages of a step.
enum class HostField
{
  DensityAndLambda, // after the density pass
  Predicted,        // p, after each position correction
  Velocity,         // after the velocity update
  Vorticity,        // omega and XSPH's sum, before the confinement
  Normal            // grad c smoothed (smoothColour), before the confinement
};

} // namespace pbf
