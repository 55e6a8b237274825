// The step of DeviceSubdomainStepper as StepLoop.h's Loop (its parts 1-4 are the Loop's predict
// and findNeighbours; part 5, the passes over the owned particles, its stages), the adaptive
// reduction over the ranks, and the owned particles kept in cell order.
// Included at the end of DeviceSubdomainStepper.h; not a header of its own.
#pragma once

namespace pbf::cuda
{

// The Loop of StepLoop.h for one rank's GPU sub-domain: each pass over the owned particles runs
// as two launches, the border particles (the columns a neighbour mirrors) on the border stream
// and then the interior ones, the border's fields on their way to the neighbours while the
// interior runs (twoSided). Adaptive mode's compression is reduced over every rank's owned
// particles after each density pass, as SubdomainStepper's is (per rank in fixed blocks, then the
// ranks in order), so every rank ends the solve after the same projection.
template <class Real, class Device>
class DeviceSubdomainStepper<Real, Device>::Loop
{
public:
  explicit Loop(DeviceSubdomainStepper& s)
    : s_(s)
    , device_(*s.device_)
    , k_(s.constants_)
    , start_(Clock::now())
  {
  }

  // x, v and the predicted positions in the free buffer. The prediction does not depend on the
  // cut, so it runs first and the cut's one wait also brings back the predicted positions'
  // column counts, from which the migration's and the ghosts' counts follow.
  void predict()
  {
    const int p = freeBuffer(s_.xBuffer_, s_.vBuffer_, -1);
    auto exec = device_.executor();
    subdomain::predict(
      exec, k_, count(s_.n_), s_.vec_[s_.xBuffer_], s_.vec_[s_.vBuffer_], s_.vec_[p]);
    s_.cut(s_.xBuffer_, p);
    r_ = Roles4{ s_.xBuffer_, p, s_.vBuffer_, otherBuffer(s_.xBuffer_, p, s_.vBuffer_) };
  }

  void findNeighbours()
  {
    r_ = s_.migrate(r_);
    r_ = s_.receiveGhosts(r_);
    keys_ = s_.sortByCell(r_);
    s_.exchange_.beforePassesMilliseconds = since(start_);
    // Now vec[r.x] = x, vec[r.p] = x*, vec[r.v] = v in cell order; vec[r.free] is free.
    n_ = count(s_.n_);
    b_ = s_.buffers();
    // The border launches count their mask builds apart, so that no counter is written by two
    // launches at once.
    edgeBuffers_ = b_;
    edgeBuffers_.maskBuilds = s_.borderMaskBuilds_;
    // The walls' sums of the border's warps come first, the interior's after them, so that one
    // reduction adds them all in a fixed order (finishSolve).
    borderWarps_ = (s_.border_ + 31u) / 32u;
    wallWarps_ = borderWarps_ + (n_ - s_.border_ + 31u) / 32u;
    if (b_.wallWarps.flags)
    {
      b_.wallWarps.flags += borderWarps_;
      b_.wallWarps.values += static_cast<std::size_t>(borderWarps_) * kWallLoadDoubles;
    }
    x_ = s_.vec_[r_.x];
    v_ = s_.vec_[r_.v];
    positions_[0] = s_.vec_[r_.p];
    positions_[1] = s_.vec_[r_.free];
    auto exec = device_.executor();
    exec.fillZero(s_.maxMoved_, static_cast<std::size_t>(k_.iterations) * sizeof(unsigned long long));
    if (k_.loads)
    {
      exec.fillZero(k_.loads,
        static_cast<std::size_t>(k_.obstacleCount) * kLoadValues * sizeof(double));
    }
    if (b_.wallWarps.flags)
    {
      exec.fillZero(b_.wallLoads, kWallLoadDoubles * sizeof(double));
      exec.fillZero(edgeBuffers_.wallWarps.flags, wallWarps_ * sizeof(std::uint32_t));
    }
  }

  // The liquids' weights compiled in only for a scene that names liquids.
  void densityAndLambda(const Projection& p)
  {
    const FluidView<Real, MaskedNeighbors<Real>> f = view(p.iteration);
    detail::withPass<detail::DensityPass>(b_.liquid != nullptr, [&](auto pass) {
      twoSided<Real>(
        [&](auto& exec, const StepBuffers<Real>& b, std::uint32_t n, detail::ListedParticles on) {
          detail::firstPassOnPositions(
            exec, DensityStage<Real>{}, b, k_, n, f, p.iteration, false, pass, on);
        },
        s_.density_, s_.lambda_);
    });
  }

  void measureCompression(const Projection&, bool mayStop)
  {
    const Compression c = s_.compression(n_);
    s_.report_.densityError = c.mean;
    stopped_ = mayStop &&
      c.within(s_.parameters_.densityErrorTolerance, s_.parameters_.maxDensityErrorTolerance);
  }

  // This rank's owned particles' share, into k.loads; the ranks' are added after the solve.
  void sumLoads(const Projection& p)
  {
    if (stopped_)
    {
      return;
    }
    auto exec = device_.executor();
    detail::loadsPass(
      exec, k_, n_, view(p.iteration), nullptr, detail::ListedParticles{ s_.ownedList_ });
  }

  // Chebyshev's blend reads each owned particle's own positions two projections back, which
  // the other position buffer still holds (StepSchedule.h's correctionPass). The last
  // correction the count allows also updates the velocities, which XSPH and vorticity read.
  void correct(const Projection& p)
  {
    if (stopped_)
    {
      return;
    }
    const FluidView<Real, MaskedNeighbors<Real>> f = view(p.iteration);
    const Real omega = static_cast<Real>(p.omega);
    twoSided<Vec3<Real>>(
      [&](auto& exec, const StepBuffers<Real>& b, std::uint32_t n, detail::ListedParticles on) {
        detail::correctionPass(
          exec, b, n, f, p.iteration, p.last, nullptr, p.accelerate, omega, on);
      },
      f.scratch, p.last ? v_ : nullptr);
    ++performed_;
  }

  template <class Body>
  void whileCompressed(int first, int end, Body&& body)
  {
    for (int k = first; k < end && !stopped_; ++k)
    {
      body(*this, k);
    }
  }

  // A solve that stopped early: its last correction did not know it was the last, so line 21
  // runs here for the positions reached.
  void finishSolve()
  {
    auto exec = device_.executor();
    detail::sumWallLoads(exec, edgeBuffers_, wallWarps_, detail::ListedParticles{});
    finishLoads();
    if (k_.tolerance > 0)
    {
      s_.report_.iterations = performed_;
    }
    else
    {
      s_.report_.iterations = k_.iterations;
      s_.report_.densityError = std::numeric_limits<double>::quiet_NaN();
    }
    if (!stopped_)
    {
      return;
    }
    const FluidView<Real, MaskedNeighbors<Real>> apply = view(performed_);
    twoSided<Vec3<Real>>(
      [&](auto& exec, const StepBuffers<Real>&, std::uint32_t n, detail::ListedParticles on) {
        subdomain::updateVelocities<Real>(exec, n, on.list, apply);
      },
      v_, nullptr);
  }

  // Omega into x's buffer and XSPH's sum into the other position buffer; the ghosts' omega, and
  // their XSPH sums where the bi-Laplacian reads them. With surface tension the same pass sums
  // the colour gradients, refreshed with omega, and a pass of their own smooths them into the
  // normals, refreshed too: the confinement reads both of its neighbours (SurfaceTension.h).
  // The solids' images are compiled in only where the scene has solids, as on one GPU.
  void vorticityAndXsph()
  {
    const StepConstants<Real> after = afterConstants();
    const FluidView<Real, MaskedNeighbors<Real>> f = afterView();
    Vec3<Real>* const ghostSmoothing = s_.parameters_.xsphHyperViscosity > 0 ? f.smoothing : nullptr;
    auto run = [&](auto pass) {
      twoSided<Vec3<Real>>(
        [&](auto& exec, const StepBuffers<Real>& b, std::uint32_t n, detail::ListedParticles on) {
          detail::firstPassOnPositions(exec, typename decltype(pass)::Stage{}, b, after, n, f,
            performed_, false, pass, on);
        },
        x_, ghostSmoothing, f.colour);
    };
    const bool friction = k_.c.wallFriction != Real(0);
    if (f.colour && f.obstacleCount > 0)
    {
      detail::withPass<detail::SolidColourVorticityPass>(friction, run);
      smoothColour<true>(f);
    }
    else if (f.colour)
    {
      detail::withPass<detail::ColourVorticityPass>(friction, run);
      smoothColour<false>(f);
    }
    else
    {
      detail::withPass<detail::PlainVorticityPass>(friction, run);
    }
  }

  // The velocities in place (omega = x, XSPH's sum = f.scratch: the neighbours read both).
  void confine()
  {
    auto exec = device_.executor();
    subdomain::confine<Real>(exec, n_, s_.ownedList_, afterView());
  }

  // Line 23 and the ghosts dropped: x = the corrected positions, v, owned only, into the
  // buffers that held omega and XSPH's sum.
  void commit()
  {
    const FluidView<Real, MaskedNeighbors<Real>> f = afterView();
    s_.keepOwned(f.p, v_, r_.x, f.scratch == s_.vec_[r_.p] ? r_.p : r_.free);
  }

private:
  // The step's loads, the solids' then the walls': every rank's sums added in rank order, as the
  // CPU sub-domain adds them.
  void finishLoads()
  {
    const std::size_t solids = static_cast<std::size_t>(k_.obstacleCount);
    const std::size_t walls = b_.wallLoads ? kMirrorWalls : 0;
    s_.report_.loads.clear();
    if (solids + walls == 0)
    {
      return;
    }
    std::vector<double> mine((solids + walls) * kLoadValues);
    if (solids > 0)
    {
      device_.download(mine.data(), k_.loads, solids * kLoadValues * sizeof(double));
    }
    if (walls > 0)
    {
      device_.download(
        mine.data() + solids * kLoadValues, b_.wallLoads, kWallLoadDoubles * sizeof(double));
    }
    device_.synchronize();
    const std::vector<double> all = distributed::sumInRankOrder(s_.communicator_, mine);
    s_.report_.loads.resize(solids + walls);
    for (std::size_t o = 0; o < solids + walls; ++o)
    {
      const double* v = &all[o * kLoadValues];
      s_.report_.loads[o].force = Vec3d{ v[0], v[1], v[2] };
      s_.report_.loads[o].torque = Vec3d{ v[3], v[4], v[5] };
    }
  }

  // pass(executor, buffers, count, particles) over the border particles on the border stream,
  // the fields a (and b) of the send lists on their way out, the same pass over the interior
  // beside them, then the neighbours' fields into the ghost slots before the next pass.
  template <class T, class Pass>
  void twoSided(Pass&& pass, T* a, T* b, T* c = nullptr)
  {
    const auto fields = subdomain::RefreshFields<T>::of(a, b, c);
    auto exec = device_.executor();
    auto edge = device_.borderExecutor();
    device_.forkBorder();
    pass(edge, edgeBuffers_, s_.border_, detail::ListedParticles{ s_.borderList_ });
    s_.template sendRefresh<T>(fields);
    pass(exec, b_, n_ - s_.border_, detail::ListedParticles{ s_.interiorList_ });
    device_.joinBorder();
    s_.template receiveRefresh<T>(fields);
  }

  // The colour gradients (the ghosts' refreshed) smoothed into the normals, border first, and
  // the ghosts' normals refreshed.
  template <bool Solids>
  void smoothColour(const FluidView<Real, MaskedNeighbors<Real>>& f)
  {
    twoSided<Vec3<Real>>(
      [&](auto& exec, const StepBuffers<Real>&, std::uint32_t n, detail::ListedParticles on) {
        detail::smoothColourPass<Solids>(exec, n, f, on);
      },
      f.normal, nullptr);
  }

  FluidView<Real, MaskedNeighbors<Real>> view(int iteration) const
  {
    return detail::iterationView(b_, k_, keys_, x_, v_, positions_, iteration);
  }

  // The passes after the solve read the positions the last projection wrote.
  StepConstants<Real> afterConstants() const
  {
    StepConstants<Real> after = k_;
    after.iterations = performed_;
    return after;
  }
  FluidView<Real, MaskedNeighbors<Real>> afterView() const
  {
    return detail::afterIterationsView(b_, afterConstants(), keys_, x_, v_, positions_);
  }

  DeviceSubdomainStepper& s_;
  Device& device_;
  const StepConstants<Real>& k_;
  Clock::time_point start_;
  Roles4 r_{};
  const CellKey* keys_ = nullptr;
  std::uint32_t n_ = 0;
  StepBuffers<Real> b_{};
  StepBuffers<Real> edgeBuffers_{};
  Vec3<Real>* x_ = nullptr;
  Vec3<Real>* v_ = nullptr;
  Vec3<Real>* positions_[2] = {};
  int performed_ = 0;
  bool stopped_ = false;
  std::uint32_t borderWarps_ = 0; // the border's warps of the walls' sums
  std::uint32_t wallWarps_ = 0;   // the border's and the interior's
};

// With several liquids each rank gives each liquid's sum and count (AdaptiveState's), and the
// mean is the most compressed liquid's over all ranks, as SubdomainStepper's.
template <class Real, class Device>
Compression DeviceSubdomainStepper<Real, Device>::compression(std::uint32_t n)
{
  auto exec = device_->executor();
  subdomain::gather<Real>(exec, n, ownedList_, density_, densityAlt_);
  const bool byLiquid = liquid_ && parameters_.liquidCount() > 1;
  if (byLiquid)
  {
    subdomain::gather<Real>(exec, n, ownedList_, liquid_, liquidAlt_);
  }
  // A negative tolerance: the state only reports, the loop here decides.
  exec.fillZero(adaptive_, sizeof(AdaptiveState));
  exec.reduceCompression(
    densityAlt_, byLiquid ? liquidAlt_ : nullptr, n, adaptive_, blockSums_, constants_, -1.0);
  AdaptiveState state{};
  device_->download(&state, adaptive_, sizeof state);
  device_->synchronize();
  const std::size_t liquids = byLiquid ? static_cast<std::size_t>(parameters_.liquidCount()) : 1;
  // Sums, then counts, per liquid; then the largest.
  std::vector<double> mine(2 * liquids + 1);
  for (std::size_t l = 0; l < liquids; ++l)
  {
    mine[l] = byLiquid ? state.liquidSum[l] : state.densityError * double(n);
    mine[liquids + l] = byLiquid ? state.liquidCount[l] : double(n);
  }
  mine[2 * liquids] = state.maxDensityError;
  std::vector<double> total(2 * liquids, 0.0);
  Compression c;
  for (const std::vector<double>& r : distributed::allGather(communicator_, mine))
  {
    for (std::size_t k = 0; k < 2 * liquids; ++k)
    {
      total[k] += r[k];
    }
    c.max = std::max(c.max, r[2 * liquids]);
  }
  for (std::size_t l = 0; l < liquids; ++l)
  {
    c.mean = std::max(c.mean, total[liquids + l] > 0 ? total[l] / total[liquids + l] : 0.0);
  }
  return c;
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::keepOwned(const Vec3<Real>* x,
  const Vec3<Real>* v,
  int toX,
  int toV)
{
  if (total_ == n_)
  {
    // No ghosts (one rank): the owned particles are all of them, in place.
    for (int i = 0; i < 4; ++i)
    {
      if (vec_[i] == x)
      {
        xBuffer_ = i;
      }
      if (vec_[i] == v)
      {
        vBuffer_ = i;
      }
    }
    return;
  }
  auto exec = device_->executor();
  const std::uint32_t n = count(n_);
  subdomain::gather<Real>(exec, n, ownedList_, x, vec_[toX]);
  subdomain::gather<Real>(exec, n, ownedList_, v, vec_[toV]);
  subdomain::gather<Real>(exec, n, ownedList_, density_, densityAlt_);
  subdomain::gather<Real>(exec, n, ownedList_, lambda_, lambdaAlt_);
  subdomain::gather<Real>(exec, n, ownedList_, pressure_, pressureAlt_);
  subdomain::gather<Real>(exec, n, ownedList_, id_, idAlt_);
  if (liquid_)
  {
    subdomain::gather<Real>(exec, n, ownedList_, liquid_, liquidAlt_);
  }
  store_->swapAlternates();
  adoptStore();
  xBuffer_ = toX;
  vBuffer_ = toV;
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::evaluateAtRest()
{
  auto exec = device_->executor();
  const int p = freeBuffer(xBuffer_, vBuffer_, -1);
  exec.copy(vec_[p], vec_[xBuffer_], n_ * sizeof(Vec3<Real>));
  Roles4 r{ xBuffer_, p, vBuffer_, otherBuffer(xBuffer_, p, vBuffer_) };
  r = migrate(r);
  r = receiveGhosts(r);
  const CellKey* keys = sortByCell(r);
  exec = device_->executor();
  const StepBuffers<Real> b = buffers();
  FluidView<Real, MaskedNeighbors<Real>> f = detail::solverView(b, constants_, keys);
  f.p = vec_[r.p];
  detail::withPass<detail::DensityPass>(liquid_ != nullptr, [&](auto pass) {
    detail::firstPassOnPositions(exec, DensityStage<Real>{}, b, constants_, count(n_), f, 0, false,
      pass, detail::ListedParticles{ ownedList_ });
  });
  // The pressure's mean goes on (the sort carried it); appended particles start at 0.
  keepOwned(vec_[r.x], vec_[r.v], r.p, r.free);
  device_->synchronize();
  checkLists();
}

} // namespace pbf::cuda
