// The Loop of StepLoop.h over a HostFluid: how the stages of a step run on the CPU, for the serial
// and OpenMP stepper and one rank's CPU sub-domain. What differs between the two comes from the
// stepper, which has these members (HostStepLoop is their friend):
//   forEach(stage)       runs stage(i) over the particles it owns, in parallel or not
//   refresh(field)       brings that field of the particles it does not own (its ghosts) up to
//                        date; nothing to do when it owns them all
//   compression()        the whole fluid's mean and largest compression (collective)
//   ownedCount(), forEachInBlocks(block, stage)   stage(b, i) for the owned particles, the
//                        k-th of them in block b = k / block; blocks in parallel or not, each
//                        block's particles in order
//   sumOverRanks(values) the values summed over the ranks in rank order (collective)
//   predict(), findNeighbours()   Algorithm 1's lines 1-7 (a sub-domain also cuts, migrates and
//                        receives its ghosts there)
#pragma once

#include "HostFluid.h"
#include "StepLoop.h"
#include "WallLoads.h"

#include <cstddef>
#include <limits>
#include <vector>

namespace pbf
{

template <class Real, class Owner>
class HostStepLoop
{
public:
  HostStepLoop(HostFluid<Real>& fluid, Owner& owner, StepReport& report)
    : fluid_(fluid)
    , owner_(owner)
    , report_(report)
  {
  }

  void predict() { owner_.predict(); }
  void findNeighbours()
  {
    owner_.findNeighbours();
    // The sort swaps the arrays with their gathered copies and a sub-domain's migration resizes
    // them: the views are taken after.
    f_ = fluid_.view();
    first_ = fluid_.view(true);
  }

  void densityAndLambda(const Projection&)
  {
    const FluidView<Real>& f = f_;
    owner_.forEach([&](std::uint32_t i) { pbf::densityAndLambda(i, f); });
    owner_.refresh(HostField::DensityAndLambda);
  }

  void measureCompression(const Projection&, bool mayStop)
  {
    const Compression c = owner_.compression();
    report_.densityError = c.mean;
    const Parameters& parameters = fluid_.parameters;
    stopped_ = mayStop &&
      c.within(parameters.densityErrorTolerance, parameters.maxDensityErrorTolerance);
  }

  void correct(const Projection& p)
  {
    if (stopped_)
    {
      return;
    }
    const FluidView<Real>& f = f_;
    const FluidView<Real>& pass = p.tensile ? first_ : f_;
    if (loadsOpen_ && fluid_.parameters.sumsWallLoads())
    {
      correctSummingWallLoads(pass);
    }
    else
    {
      owner_.forEach([&](std::uint32_t i) { positionCorrection(i, pass); });
    }
    if (loadsOpen_)
    {
      finishLoads();
    }
    if (fluid_.parameters.chebyshevRho > 0)
    {
      // Chebyshev's positions two projections back (Chebyshev.h) live in omega's array, which
      // the solve does not use: each projection leaves there the positions it started from,
      // which the next one's blend reads as p^{k-1}.
      Vec3<Real>* const twoBack = fluid_.omega.data();
      const Real omega = static_cast<Real>(p.omega);
      const bool accelerate = p.accelerate;
      owner_.forEach([&](std::uint32_t i) {
        const Vec3<Real> before = f.p[i];
        applyCorrection(i, f);
        if (accelerate)
        {
          f.p[i] = acceleratedCorrection(f.p[i], twoBack[i], omega, f);
        }
        twoBack[i] = before;
      });
    }
    else
    {
      owner_.forEach([&](std::uint32_t i) { applyCorrection(i, f); });
    }
    owner_.refresh(HostField::Predicted);
    ++report_.iterations;
  }

  // Summed in fixed blocks of particles, then the blocks in order, then the ranks in order: the
  // same bits whatever the number of threads, as compression() sums. Per solid, then per mirror
  // wall (2 a + 0 for the low wall of axis a, + 1 for the high): the solids' here, the walls' in
  // the correction that follows (its mirror images' terms, positionCorrection's onWall), and the
  // blocks are reduced after it (finishLoads).
  void sumLoads(const Projection& p)
  {
    loadsOpen_ = false;
    const std::size_t loads = loadCount();
    if (stopped_ || loads == 0)
    {
      return;
    }
    const std::size_t blocks = (owner_.ownedCount() + kLoadBlock - 1) / kLoadBlock;
    blockLoads_.assign(blocks * loads * kLoadValues, 0.0);
    loadsOpen_ = true;
    if (fluid_.obstacles.empty())
    {
      return;
    }
    const FluidView<Real>& f = p.tensile ? first_ : f_;
    owner_.forEachInBlocks(kLoadBlock,
      [&](std::size_t b, std::uint32_t i) { solidLoads(i, f, loadAdder(b, 0)); });
  }
  template <class Body>
  void whileCompressed(int first, int end, Body&& body)
  {
    for (int k = first; k < end && !stopped_; ++k)
    {
      body(*this, k);
    }
  }

  // Line 21 always runs here: the CPU's correction pass does not fuse it.
  void finishSolve()
  {
    if (!(fluid_.parameters.densityErrorTolerance > 0))
    {
      report_.densityError = std::numeric_limits<double>::quiet_NaN();
    }
    const FluidView<Real>& f = f_;
    owner_.forEach([&](std::uint32_t i) { updateVelocity(i, f); });
    owner_.refresh(HostField::Velocity);
  }

  void vorticityAndXsph()
  {
    const FluidView<Real>& f = f_;
    owner_.forEach([&](std::uint32_t i) { pbf::vorticityAndXsph(i, f); });
    owner_.refresh(HostField::Vorticity);
    if (f.normal)
    {
      owner_.forEach([&](std::uint32_t i) { smoothColour(i, f); });
      owner_.refresh(HostField::Normal);
    }
  }

  // The velocity in place: each particle reads only its own.
  void confine()
  {
    const FluidView<Real>& f = f_;
    owner_.forEach([&](std::uint32_t i) { vorticityConfinement(i, f, f.v); });
  }

  void commit()
  {
    const FluidView<Real>& f = f_;
    Vec3<Real>* const x = fluid_.x.data();
    owner_.forEach([&](std::uint32_t i) { commitPosition(i, f, x); });
  }

private:
  HostFluid<Real>& fluid_;
  Owner& owner_;
  StepReport& report_;
  FluidView<Real> f_{};
  FluidView<Real> first_{}; // the first projection's view, which adds s_corr
  bool stopped_ = false;
  // positionCorrection of every owned particle, its mirror images' terms summed per wall into the
  // load blocks: each particle's terms per wall, then as one force at its foot on the wall.
  void correctSummingWallLoads(const FluidView<Real>& pass)
  {
    const std::size_t firstWall = fluid_.obstacles.size();
    const Real scale = wallLoadScale<Real>(pass);
    owner_.forEachInBlocks(kLoadBlock, [&](std::size_t b, std::uint32_t i) {
      WallPush<Real> push;
      positionCorrection(i, pass, WallTerms<Real>{ push, pass.c.boxMin });
      const auto add = loadAdder(b, firstWall);
      for (int w = 0; w < kMirrorWalls; ++w)
      {
        if (!(push.touched & (1u << w)))
        {
          continue;
        }
        Vec3<Real> force, torque;
        push.load(w, pass.p[i], scale, pass.c.boxMin, pass.c.boxMax, force, torque);
        add(w, force, torque);
      }
    });
  }

  // The loads: the solids', then with Parameters::tankLoads the six mirror walls'.
  std::size_t loadCount() const
  {
    return fluid_.obstacles.size() + (fluid_.parameters.sumsWallLoads() ? kMirrorWalls : 0);
  }

  // add(o, force, torque) into block b's sums of load first + o.
  auto loadAdder(std::size_t b, std::size_t first)
  {
    return [this, b, first](int o, const Vec3<Real>& force, const Vec3<Real>& torque) {
      const std::size_t k = b * loadCount() + first + static_cast<std::size_t>(o);
      double* sum = &blockLoads_[k * kLoadValues];
      sum[0] += force.x;
      sum[1] += force.y;
      sum[2] += force.z;
      sum[3] += torque.x;
      sum[4] += torque.y;
      sum[5] += torque.z;
    };
  }

  // The blocks in order, then the ranks in order, added to the step's loads.
  void finishLoads()
  {
    const std::size_t loads = loadCount();
    const std::size_t blocks = blockLoads_.size() / (loads * kLoadValues);
    std::vector<double> mine(loads * kLoadValues, 0.0);
    for (std::size_t b = 0; b < blocks; ++b)
    {
      for (std::size_t k = 0; k < mine.size(); ++k)
      {
        mine[k] += blockLoads_[b * mine.size() + k];
      }
    }
    const std::vector<double> all = owner_.sumOverRanks(mine);
    report_.loads.resize(loads);
    for (std::size_t o = 0; o < loads; ++o)
    {
      const double* v = &all[o * kLoadValues];
      report_.loads[o].force += Vec3d{ v[0], v[1], v[2] };
      report_.loads[o].torque += Vec3d{ v[3], v[4], v[5] };
    }
    loadsOpen_ = false;
  }

  static constexpr std::size_t kLoadBlock = 512; // small enough to share out evenly
  static constexpr std::size_t kLoadValues = 6; // force and torque
  std::vector<double> blockLoads_; // per block, per load: force and torque
  bool loadsOpen_ = false;         // this projection's loads are being summed
};

} // namespace pbf
