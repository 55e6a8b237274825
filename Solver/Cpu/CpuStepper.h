// The CPU backends: Serial is the reference; OpenMP runs the very same per-particle functions
// with the loops split over threads. Nothing is summed across particles inside a step, so the two
// are bit-identical by construction.
#pragma once

#include "HostStepLoop.h"
#include "HostStepper.h"

#include <vector>

namespace pbf
{

template <class Real>
class CpuStepper final : public HostStepper<Stepper, Real>
{
public:
  CpuStepper(bool parallel, const Parameters& parameters, const ParticleBatch& initial);

  void step() override;
  void append(const ParticleBatch& batch) override;
  std::string description() const override;
  Statistics statistics() const override;
  Health health() const override;
  // Density and lambda are evaluated again at the current positions, with the solids.
  void setObstacles(
    const std::vector<DistanceGrid>& obstacles, const std::vector<SolidPose>& poses = {}) override
  {
    fluid_.setObstacles(obstacles, poses);
    evaluateDensityAtRest();
  }
  void setObstaclePoses(const std::vector<SolidPose>& poses) override { fluid_.setPoses(poses); }
  std::size_t removeOutflow(const std::vector<Box>& zones) override
  {
    const std::size_t removed =
      removeInside(OutflowZones<Real>::make(zones), fluid_.particles());
    fluid_.resizeWork(fluid_.x.size());
    return removed;
  }
  // Nothing else is state: the next step predicts, re-sorts (stably, from this order) and
  // recomputes every other array.
  void load(const Snapshot<float>& state) override { loadState(state); }
  void load(const Snapshot<double>& state) override { loadState(state); }

private:
  // The stages of a step that are this stepper's own (HostStepLoop.h).
  friend class HostStepLoop<Real, CpuStepper>;
  void predict();
  void findNeighbours() { sortByCell(); }
  template <class Stage>
  void forEach(Stage&& stage) { forEachParticle(stage); }
  void refresh(HostField) {} // every particle is this stepper's own
  std::size_t ownedCount() const { return fluid_.x.size(); }
  template <class Stage>
  void forEachInBlocks(std::size_t block, Stage&& stage)
  {
    pbf::forEachInBlocks(parallel_, fluid_.x.size(), block,
      [](std::size_t k) { return static_cast<std::uint32_t>(k); }, stage);
  }
  std::vector<double> sumOverRanks(const std::vector<double>& mine) const { return mine; }

  template <class In>
  void loadState(const Snapshot<In>& state)
  {
    loadFromSnapshot(fluid_.parameters, state, fluid_.particles());
    fluid_.resizeWork(fluid_.x.size());
  }
  // Mean and max of max(rho_i / rho_0 - 1, 0) of density_, summed in fixed blocks: thread-count
  // independent.
  Compression compression();
  template <class Stage>
  void forEachParticle(Stage&& stage);
  void sortByCell();             // keys from p_, counting sort, gather every array
  void evaluateDensityAtRest(); // density and lambda of the current positions, nothing moves

  using HostStepper<Stepper, Real>::parallel_;
  using HostStepper<Stepper, Real>::fluid_;
  using HostStepper<Stepper, Real>::report_;
  std::vector<double> blockSums_;
};

} // namespace pbf
