// The solve of DeviceSubdomainStepper (its step 5): the passes of a step over the owned particles,
// border first and interior beside the exchange, the adaptive reduction over the ranks, and the
// owned particles kept in cell order.
// Included at the end of DeviceSubdomainStepper.h; not a header of its own.
#pragma once

namespace pbf::cuda
{

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::solve(Roles4 r, const CellKey* sortedKeys)
{
  const std::uint32_t n = count(n_);
  const std::uint32_t border = border_;
  const std::uint32_t interior = n - border;
  const detail::ListedParticles onBorder{ borderList_ };
  const detail::ListedParticles onInterior{ interiorList_ };
  const StepConstants<Real>& k = constants_;
  const StepBuffers<Real> b = buffers();
  auto exec = device_->executor();
  Vec3<Real>* const x = vec_[r.x];
  Vec3<Real>* const v = vec_[r.v];
  Vec3<Real>* const positions[2] = { vec_[r.p], vec_[r.free] };
  exec.fillZero(maxMoved_, static_cast<std::size_t>(k.iterations) * sizeof(unsigned long long));
  // The border launches run on the device's border stream, beside the interior ones (the two
  // write disjoint particles; interior particles read no ghost); their mask builds are counted
  // apart, so that no counter is written by two launches at once.
  StepBuffers<Real> edgeBuffers = b;
  edgeBuffers.maskBuilds = borderMaskBuilds_;
  const StepBuffers<Real>& be = edgeBuffers;
  // Adaptive mode: the mean compression over every rank's owned particles after each density
  // pass, as SubdomainStepper::meanDensityError has it (per rank in fixed blocks, then the
  // ranks in order); after the first projection the loop ends once it is within the tolerance,
  // and the velocities are then updated from the positions reached.
  const bool adaptive = k.tolerance > 0;
  int performed = 0;
  bool converged = false;
  for (int iteration = 0; iteration < k.iterations; ++iteration)
  {
    const FluidView<Real, MaskedNeighbors<Real>> f =
      detail::iterationView(b, k, sortedKeys, x, v, positions, iteration);
    exec = device_->executor();
    auto edge = device_->borderExecutor();
    device_->forkBorder();
    detail::firstPassOnPositions(
      edge, DensityStage<Real>{}, be, k, border, f, iteration, false, detail::DensityPass{}, onBorder);
    sendRefresh<Real>(density_, lambda_);
    detail::firstPassOnPositions(
      exec, DensityStage<Real>{}, b, k, interior, f, iteration, false, detail::DensityPass{}, onInterior);
    device_->joinBorder();
    receiveRefresh<Real>(density_, lambda_);
    if (adaptive)
    {
      const Compression c = compression(n);
      report_.densityError = c.mean;
      if (iteration > 0 &&
        c.within(parameters_.densityErrorTolerance, parameters_.maxDensityErrorTolerance))
      {
        converged = true;
        break;
      }
    }
    const bool last = iteration + 1 == k.iterations;
    // Chebyshev's blend reads each owned particle's own positions two projections back, which
    // the other position buffer still holds (StepSchedule.h's correctionPass).
    const bool accelerate = k.chebyshevRho > 0 && iteration > 0;
    const Real omega = static_cast<Real>(chebyshevWeight(k.chebyshevRho, iteration));
    exec = device_->executor();
    device_->forkBorder();
    detail::correctionPass(
      edge, be, border, f, iteration, last, nullptr, accelerate, omega, onBorder);
    // The last correction also updates the velocities, which XSPH and vorticity read.
    sendRefresh<Vec3<Real>>(f.scratch, last ? v : nullptr);
    detail::correctionPass(
      exec, b, interior, f, iteration, last, nullptr, accelerate, omega, onInterior);
    device_->joinBorder();
    receiveRefresh<Vec3<Real>>(f.scratch, last ? v : nullptr);
    ++performed;
  }
  if (adaptive)
  {
    report_.iterations = performed;
  }
  if (converged)
  {
    // The last correction did not know it was the last: line 21 for the positions reached,
    // border particles first so that their velocities travel while the interior's are set.
    FluidView<Real, MaskedNeighbors<Real>> apply =
      detail::iterationView(b, k, sortedKeys, x, v, positions, performed);
    exec = device_->executor();
    auto edge = device_->borderExecutor();
    device_->forkBorder();
    subdomain::updateVelocities<Real>(edge, border, borderList_, apply);
    sendRefresh<Vec3<Real>>(v, nullptr);
    subdomain::updateVelocities<Real>(exec, interior, interiorList_, apply);
    device_->joinBorder();
    receiveRefresh<Vec3<Real>>(v, nullptr);
  }
  // The passes after the iterations read the positions the last projection wrote.
  StepConstants<Real> after = k;
  after.iterations = performed;
  const FluidView<Real, MaskedNeighbors<Real>> f =
    detail::afterIterationsView(b, after, sortedKeys, x, v, positions);
  exec = device_->executor();
  // The ghosts' omega, and their XSPH sums where the bi-Laplacian reads them.
  Vec3<Real>* const ghostSmoothing = parameters_.xsphHyperViscosity > 0 ? f.smoothing : nullptr;
  detail::withPass<detail::VorticityPass>(k.c.wallFriction != Real(0), [&](auto pass) {
    {
      auto edge = device_->borderExecutor();
      device_->forkBorder();
      detail::firstPassOnPositions(
        edge, typename decltype(pass)::Stage{}, be, after, border, f, performed, false, pass, onBorder);
    }
    sendRefresh<Vec3<Real>>(x, ghostSmoothing);
    detail::firstPassOnPositions(
      exec, typename decltype(pass)::Stage{}, b, after, interior, f, performed, false, pass, onInterior);
  });
  device_->joinBorder();
  receiveRefresh<Vec3<Real>>(x, ghostSmoothing);
  exec = device_->executor();
  // The velocities in place (omega = x, XSPH's sum = f.scratch: the neighbours read both).
  subdomain::confine<Real>(exec, n, ownedList_, f);
  // Line 23 and the ghosts dropped: x = the corrected positions, v, owned only, into the
  // buffers that held omega and XSPH's sum.
  keepOwned(f.p, v, r.x, f.scratch == vec_[r.p] ? r.p : r.free);
}

template <class Real, class Device>
Compression DeviceSubdomainStepper<Real, Device>::compression(std::uint32_t n)
{
  auto exec = device_->executor();
  subdomain::gather<Real>(exec, n, ownedList_, density_, densityAlt_);
  // A negative tolerance: the state only reports, the loop here decides.
  exec.fillZero(adaptive_, sizeof(AdaptiveState));
  exec.reduceCompression(densityAlt_, n, adaptive_, blockSums_, constants_, -1.0);
  AdaptiveState state{};
  device_->download(&state, adaptive_, sizeof state);
  device_->synchronize();
  double total = 0.0, count = 0.0;
  Compression c;
  for (const std::vector<double>& r : distributed::allGather(
         communicator_, { state.densityError * double(n), double(n), state.maxDensityError }))
  {
    total += r[0];
    count += r[1];
    c.max = std::max(c.max, r[2]);
  }
  c.mean = count > 0 ? total / count : 0.0;
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
  subdomain::gather<Real>(exec, n, ownedList_, id_, idAlt_);
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
  detail::firstPassOnPositions(exec,
    DensityStage<Real>{},
    b,
    constants_,
    count(n_),
    f,
    0,
    false,
    detail::DensityPass{},
    detail::ListedParticles{ ownedList_ });
  keepOwned(vec_[r.x], vec_[r.v], r.p, r.free);
  device_->synchronize();
  checkLists();
}

} // namespace pbf::cuda
