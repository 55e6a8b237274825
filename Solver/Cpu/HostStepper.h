// The part of the Stepper interface that follows from keeping the particles in a HostFluid, for
// the serial/OpenMP stepper (Base = Stepper) and one rank's CPU sub-domain (Base =
// distributed::DecomposedStepper): the count, the backend, the precision, the state out, the time
// step and the last step's report.
#pragma once

#include "HostFluid.h"
#include "Stepper.h"

namespace pbf
{

template <class Base, class Real>
class HostStepper : public Base
{
public:
  std::size_t size() const override { return fluid_.x.size(); }
  Backend backend() const override { return parallel_ ? Backend::OpenMP : Backend::Serial; }
  Precision precision() const override { return fluid_.precision(); }
  void read(Snapshot<float>& out) const override
  {
    copyToSnapshot(fluid_.parameters, fluid_.particles(), out);
  }
  void read(Snapshot<double>& out) const override
  {
    copyToSnapshot(fluid_.parameters, fluid_.particles(), out);
  }
  void setTimeStep(double dt, double pressureElapsed = 0) override
  {
    fluid_.setTimeStep(dt, pressureElapsed);
  }
  double timeStep() const override { return fluid_.dt; }
  StepReport lastStep() const override { return report_; }

protected:
  HostStepper(bool parallel, const Parameters& parameters)
    : parallel_(parallel)
    , fluid_(parameters)
  {
  }

  bool parallel_;
  HostFluid<Real> fluid_;
  StepReport report_;
};

} // namespace pbf
