// The CPU backends: Serial is the reference; OpenMP runs the very same per-particle functions
// with the loops split over threads. Nothing is summed across particles inside a step, so the two
// are bit-identical by construction.
#pragma once

#include "Equations.h"
#include "HostParticles.h"
#include "Stepper.h"

#include <vector>

namespace pbf
{

template <class Real>
class CpuStepper final : public Stepper
{
public:
  CpuStepper(bool parallel, const Parameters& parameters, const ParticleBatch& initial);

  void step() override;
  void append(const ParticleBatch& batch) override;
  void setTimeStep(double dt) override;
  double timeStep() const override { return dt_; }

  std::size_t size() const override { return x_.size(); }
  Backend backend() const override { return parallel_ ? Backend::OpenMP : Backend::Serial; }
  Precision precision() const override;
  std::string description() const override;

  void read(Snapshot<float>& out) const override { copyOut(out); }
  void read(Snapshot<double>& out) const override { copyOut(out); }

  Statistics statistics() const override;
  Health health() const override;
  StepReport lastStep() const override { return report_; }
  void load(const Snapshot<float>& state) override { loadState(state); }
  void load(const Snapshot<double>& state) override { loadState(state); }

private:
  template <class Out>
  void copyOut(Snapshot<Out>& out) const;
  template <class In>
  void loadState(const Snapshot<In>& state);
  // Mean and max of max(rho_i / rho_0 - 1, 0) of density_, summed in fixed blocks: thread-count
  // independent.
  Compression compression();
  template <class Stage>
  void forEachParticle(Stage&& stage);
  FluidView<Real> view(bool tensile = false);
  HostParticles<Real> particles() { return { x_, v_, density_, lambda_, id_ }; }
  ConstHostParticles<Real> particles() const { return { x_, v_, density_, lambda_, id_ }; }
  void sortByCell();             // keys from p_, counting sort, gather every array
  void evaluateDensityAtRest(); // density and lambda of the current positions, nothing moves

  bool parallel_;
  Parameters parameters_;
  Coefficients<Real> coefficients_;
  LatticeCalibration lattice_;
  double dt_ = 0;
  StepTime<Real> time_{};
  GridGeometry<Real> geometry_;

  std::vector<Vec3<Real>> x_, p_, v_, scratch_, omega_;
  std::vector<Real> density_, lambda_;
  std::vector<double> blockSums_;
  StepReport report_;
  std::vector<std::int64_t> id_;
  std::vector<CellKey> keys_;
  std::vector<std::uint32_t> cellOffsets_, order_, cursor_;
  // Gather targets, kept to avoid allocating every step.
  std::vector<Vec3<Real>> gatherVec_;
  std::vector<std::int64_t> gatherId_;
  std::vector<CellKey> gatherKey_;
};

} // namespace pbf
