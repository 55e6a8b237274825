// The Loop of StepLoop.h for the CUDA stepper: each stage of a step queued on an executor
// (StepSchedule.h's interface), so that a step is one sequence of kernels that DeviceStepper.h
// captures as one graph. Adaptive mode's stop stays on the device: each projection after the
// first is the body of a conditional node that the reduction before it switches off.
#pragma once

#include "StepLoop.h"
#include "StepSchedule.h"

#include <vector>

namespace pbf
{
namespace cuda
{

template <class Real, class Exec>
class DeviceStepLoop
{
public:
  DeviceStepLoop(Exec& exec, const StepBuffers<Real>& b, const StepConstants<Real>& k,
    std::uint32_t n, Roles roles)
    : exec_(exec)
    , b_(b)
    , k_(k)
    , n_(n)
    , roles_(roles)
    , A_(b.vec[roles.x])
    , B_(b.vec[roles.v])
    , C_(b.vec[2])
    , D_(b.vec[3])
    , adaptive_(k.tolerance > 0)
    , proceed_(&branches_)
  {
  }

  // The same loop with another executor: the body of a conditional node (whileCompressed).
  DeviceStepLoop(const DeviceStepLoop& outer, Exec& exec)
    : exec_(exec)
    , b_(outer.b_)
    , k_(outer.k_)
    , n_(outer.n_)
    , roles_(outer.roles_)
    , A_(outer.A_)
    , B_(outer.B_)
    , C_(outer.C_)
    , D_(outer.D_)
    , adaptive_(outer.adaptive_)
    , sortedKeys_(outer.sortedKeys_)
    , proceed_(outer.proceed_)
  {
  }

  DeviceStepLoop(const DeviceStepLoop&) = delete;
  DeviceStepLoop& operator=(const DeviceStepLoop&) = delete;

  std::uint32_t wallWarps() const { return (n_ + 31u) / 32u; }

  static SolveRule rule(const StepConstants<Real>& k)
  {
    SolveRule r;
    r.iterations = k.iterations;
    r.adaptive = k.tolerance > 0;
    r.chebyshevRho = k.chebyshevRho;
    return r;
  }

  // Lines 1-4: gravity and the predicted positions x*_i, with their cell keys.
  void predict()
  {
    FluidView<Real> f = detail::plainView(k_);
    f.x = A_;
    f.v = B_;
    f.p = C_;
    CellKey* keys = b_.keys[0];
    std::uint32_t* order = reinterpret_cast<std::uint32_t*>(b_.lambda);
    const GridGeometry<Real> geometry = k_.geometry;
    exec_.forEach(PredictStage{}, n_, [=] PBF_HD(std::uint32_t i) {
      predictPosition(i, f);
      keys[i] = geometry.keyOf(f.p[i]);
      order[i] = i;
    });
  }

  // Line 7, then the solve's counters zeroed and its conditions made: they belong to the step's
  // own graph, so they are all made before its first projection.
  void findNeighbours()
  {
    sortedKeys_ = detail::sortAndGather(exec_, b_, k_, n_, A_, B_, C_, D_);
    // Now D = x, A = x*, C = v; the solver's positions alternate between A and B.
    exec_.fillZero(
      b_.maxMoved, static_cast<std::size_t>(k_.iterations) * sizeof(unsigned long long));
    if (b_.moved)
    {
      exec_.fillZero(b_.moved, static_cast<std::size_t>(n_) * sizeof(float));
      exec_.fillZero(b_.cellMoved, static_cast<std::size_t>(k_.cellCount) * sizeof(std::uint32_t));
    }
    if (adaptive_)
    {
      exec_.fillZero(b_.adaptive, sizeof(AdaptiveState));
    }
    if (k_.loads)
    {
      exec_.fillZero(k_.loads,
        static_cast<std::size_t>(k_.obstacleCount) * kLoadValues * sizeof(double));
    }
    if (b_.wallWarps.flags)
    {
      exec_.fillZero(b_.wallLoads, kWallLoadDoubles * sizeof(double));
      exec_.fillZero(b_.wallWarps.flags, wallWarps() * sizeof(std::uint32_t));
    }
    // Projection k runs when the reduction before it says so (proceed[k]).
    branches_.resize(static_cast<std::size_t>(k_.iterations) + 1);
    for (int k = 0; k <= k_.iterations; ++k)
    {
      branches_[k] =
        adaptive_ && k > 0 && k < k_.iterations ? exec_.branch() : Exec::noBranch();
    }
  }

  void densityAndLambda(const Projection& p)
  {
    detail::withPass<detail::DensityPass>(b_.liquid != nullptr, [&](auto pass) {
      detail::firstPassOnPositions(exec_, DensityStage<Real>{}, b_, k_, n_, view(p.iteration),
        p.iteration, adaptive_, pass);
    });
  }

  void measureCompression(const Projection& p, bool mayStop)
  {
    exec_.reduceCompression(b_.density, b_.liquid, n_, b_.adaptive, b_.blockSums, k_,
      mayStop ? k_.tolerance : -1.0, (*proceed_)[p.iteration + 1]);
  }

  // Into k.loads, which lastStep() reads back.
  void sumLoads(const Projection& p)
  {
    detail::loadsPass(exec_, k_, n_, view(p.iteration), adaptive_ ? b_.adaptive : nullptr);
  }

  // With a fixed count the last correction also updates the velocity (line 21); in adaptive
  // mode no correction knows it is the last, and finishSolve does.
  void correct(const Projection& p)
  {
    detail::correctionPass(exec_, b_, n_, view(p.iteration), p.iteration,
      !adaptive_ && p.last, adaptive_ ? b_.adaptive : nullptr, p.accelerate,
      static_cast<Real>(p.omega));
  }

  // Nested conditional nodes while the step is captured: a step that stops after two
  // projections skips the other conditions as one (in sequence, each skipped condition had
  // cost the graph about 3 us, 0.12 ms a step at 1.15M particles).
  template <class Body>
  void whileCompressed(int first, int end, Body&& body)
  {
    exec_.runIfChain(proceed_->data(), first, end, [&](Exec& e, int k) {
      DeviceStepLoop inner(*this, e);
      body(inner, k);
    });
  }

  // The walls' loads that the corrections' warps summed, into b.wallLoads for lastStep().
  void finishSolve()
  {
    detail::sumWallLoads(exec_, b_, wallWarps(), detail::AllParticles{});
    if (adaptive_)
    {
      detail::finishAdaptiveSolve(
        exec_, n_, view(k_.iterations), positions(), k_.iterations, b_.adaptive);
    }
  }

  // Lines 22-23 on the corrected positions. XSPH's sum goes into x's buffer and omega into the
  // other position buffer, where the confinement then writes the velocity over each particle's
  // own omega (the neighbours read |omega_j| from b.omegaLength): v ends in a buffer of x and v's
  // pair, as Roles expects.
  // With surface tension the same pass sums the colour gradients, and a pass of their own
  // smooths them into the normals (the buffers exist only then: StepBuffers::colour).
  void vorticityAndXsph()
  {
    const FluidView<Real, MaskedNeighbors<Real>> f = afterView();
    auto run = [&](auto pass) {
      detail::firstPassOnPositions(
        exec_, typename decltype(pass)::Stage{}, b_, k_, n_, f, k_.iterations, false, pass);
    };
    const bool friction = k_.c.wallFriction != Real(0);
    // The solids' images are compiled in only where the scene has solids.
    if (f.colour && f.obstacleCount > 0)
    {
      detail::withPass<detail::SolidColourVorticityPass>(friction, run);
      detail::smoothColourPass<true>(exec_, n_, f);
    }
    else if (f.colour)
    {
      detail::withPass<detail::ColourVorticityPass>(friction, run);
      detail::smoothColourPass<false>(exec_, n_, f);
    }
    else
    {
      detail::withPass<detail::PlainVorticityPass>(friction, run);
    }
  }

  void confine()
  {
    const FluidView<Real, MaskedNeighbors<Real>> f = afterView();
    Vec3<Real>* const velocity = f.scratch;
    detail::withConfinementPass(f, [&](auto pass) {
      detail::confinementPass(exec_, n_, detail::AllParticles{}, f, velocity, pass);
    });
  }

  // Line 23, x_i = x*_i: the corrected positions' buffer becomes x.
  void commit()
  {
    const bool inA = afterView().p == A_;
    next_.x = inA ? roles_.x : roles_.v;
    next_.v = inA ? roles_.v : roles_.x;
  }

  // Where x and v are after the step, and the cell keys of its sort.
  Roles next() const { return next_; }
  const CellKey* sortedKeys() const { return sortedKeys_; }

private:
  using Positions = Vec3<Real>* const[2];

  const Positions& positions() const { return positions_; }

  FluidView<Real, MaskedNeighbors<Real>> view(int iteration) const
  {
    return detail::iterationView(b_, k_, sortedKeys_, D_, C_, positions_, iteration);
  }

  FluidView<Real, MaskedNeighbors<Real>> afterView() const
  {
    FluidView<Real, MaskedNeighbors<Real>> f =
      detail::afterIterationsView(b_, k_, sortedKeys_, D_, C_, positions_);
    f.omega = f.scratch;
    f.smoothing = D_;
    return f;
  }

  Exec& exec_;
  StepBuffers<Real> b_;
  StepConstants<Real> k_;
  std::uint32_t n_;
  Roles roles_;
  Vec3<Real>* A_;
  Vec3<Real>* B_;
  Vec3<Real>* C_;
  Vec3<Real>* D_;
  Vec3<Real>* const positions_[2] = { A_, B_ };
  bool adaptive_;
  const CellKey* sortedKeys_ = nullptr;
  std::vector<typename Exec::Branch> branches_;
  std::vector<typename Exec::Branch>* proceed_; // the outermost loop's branches_
  Roles next_;
};

// Algorithm 1 of Macklin & Mueller 2013, one step queued on `exec`; returns where x and v are
// afterwards.
template <class Real, class Exec>
Roles enqueueStep(Exec& exec, const StepBuffers<Real>& b, const StepConstants<Real>& k,
  std::uint32_t n, Roles roles, const CellKey** sortedKeysOut)
{
  DeviceStepLoop<Real, Exec> loop(exec, b, k, n, roles);
  runStep(loop, DeviceStepLoop<Real, Exec>::rule(k));
  *sortedKeysOut = loop.sortedKeys();
  return loop.next();
}

} // namespace cuda
} // namespace pbf
