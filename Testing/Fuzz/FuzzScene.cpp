// libFuzzer target: the scene parser, the parameter checks and a few steps of whatever passes
// them, at a tiny size. Input: a scene (JSON text) up to the first NUL byte; after it, raw
// doubles (any bits: NaN, infinities, denormals, huge) that replace the parameters of kFields in
// order, then gravity x, y, z; then a byte of solver iterations (signed: 0 and negatives must be
// refused) and a byte of flags (1 double, 2 unilateral off, 4 mirror walls off, 8 given points,
// 16 fixed time steps). Without a NUL the defaults apply.
//
// The contract: parsing, validation and construction throw nothing but InvalidInput; advance()
// throws nothing but SimulationDiverged (the input was checked on construction). Anything else,
// another exception, a crash, a sanitizer report or a hang, is a finding.
#include "Scene.h"
#include "Simulation.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

using namespace pbf;

namespace
{

// Thousands of runs per second: only scenes this small are stepped.
constexpr double kTinyParticles = 200;
constexpr double kTinyCells = 20000;
constexpr int kSteps = 3;

double Parameters::*const kFields[] = {
  &Parameters::particleSpacing,
  &Parameters::timeStep,
  &Parameters::relaxation,
  &Parameters::smoothingRatio,
  &Parameters::restDensity,
  &Parameters::sCorrK,
  &Parameters::sCorrN,
  &Parameters::sCorrDeltaQ,
  &Parameters::xsphViscosity,
  &Parameters::xsphHyperViscosity,
  &Parameters::chebyshevRho,
  &Parameters::vorticityEpsilon,
  &Parameters::densityErrorTolerance,
  &Parameters::maxDensityErrorTolerance,
  &Parameters::cflNumber,
};
constexpr std::size_t kFieldCount = sizeof(kFields) / sizeof(kFields[0]);

struct Input
{
  std::string json;
  Parameters parameters;
  Precision precision = Precision::Single;
  bool givenPoints = false; // start from the scene's particles as given points (the VTK filter)
};

Input decode(const std::uint8_t* data, std::size_t size)
{
  Input in;
  // The solids as tangent planes: a shape map integrates seconds of a core for a large solid
  // (ShapeMap.h; its own tests cover it), which the fuzzer's per-input time limit would report as
  // a hang of every scene with a big obstacle.
  in.parameters.exactBoundaries = false;
  const auto* nul = static_cast<const std::uint8_t*>(std::memchr(data, 0, size));
  const std::uint8_t* end = data + size;
  in.json.assign(reinterpret_cast<const char*>(data),
    reinterpret_cast<const char*>(nul ? nul : end));
  if (!nul)
  {
    return in;
  }
  double* const gravity[3] = { &in.parameters.gravity.x, &in.parameters.gravity.y,
    &in.parameters.gravity.z };
  const std::uint8_t* at = nul + 1;
  for (std::size_t f = 0; f < kFieldCount + 3 && end - at >= 8; ++f, at += 8)
  {
    double value;
    std::memcpy(&value, at, sizeof value);
    if (f < kFieldCount)
    {
      in.parameters.*kFields[f] = value;
    }
    else
    {
      *gravity[f - kFieldCount] = value;
    }
  }
  if (at < end)
  {
    in.parameters.solverIterations = static_cast<std::int8_t>(*at++);
  }
  if (at < end)
  {
    const std::uint8_t flags = *at;
    in.precision = flags & 1 ? Precision::Double : Precision::Single;
    in.parameters.unilateral = !(flags & 2);
    in.parameters.mirrorWalls = !(flags & 4);
    in.givenPoints = flags & 8;
    in.parameters.timeStepping = flags & 16 ? TimeStepping::Fixed : TimeStepping::Automatic;
  }
  return in;
}

// Cells of the stepper's grid, in double so that nothing overflows.
double gridCells(const Parameters& p)
{
  const double h = p.smoothingLength();
  return std::ceil((p.domain.max.x - p.domain.min.x) / h) *
    std::ceil((p.domain.max.y - p.domain.min.y) / h) *
    std::ceil((p.domain.max.z - p.domain.min.z) / h);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const Input in = decode(data, size);
  std::unique_ptr<Simulation> simulation;
  try
  {
    const Scene scene = parseScene(in.json);
    const Parameters parameters = withSceneDomain(in.parameters, scene);
    parameters.validate();
    if (!(estimateParticleCount(scene, parameters) <= kTinyParticles) ||
      !(gridCells(parameters) <= kTinyCells))
    {
      return 0;
    }
    if (in.givenPoints)
    {
      const ParticleBatch points = fillScene(scene, parameters);
      simulation =
        std::make_unique<Simulation>(scene, parameters, Backend::Serial, in.precision, points);
    }
    else
    {
      simulation = std::make_unique<Simulation>(scene, parameters, Backend::Serial, in.precision);
    }
  }
  catch (const InvalidInput&)
  {
    return 0;
  }
  try
  {
    simulation->advance(1);
    const SimulationCheckpoint checkpoint = simulation->checkpoint();
    simulation->advance(kSteps - 1);
    simulation->restore(checkpoint);
    simulation->advance(1);
    simulation->stepper().statistics();
  }
  catch (const SimulationDiverged&)
  {
  }
  return 0;
}
