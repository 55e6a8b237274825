// pbf_bench --refined: the scene users run, refined. The dam_break preset (or any scene) at the
// given spacings, simulated frame by frame to a time as the filter does (Simulation::advanceTo),
// in three modes side by side:
//   fixed     TimeStepping Fixed: every step is MaxTimeStep (1/240 s), 4 projections per step
//             (the paper's scheme; at fine spacings it is expected to
//             diverge, and the row says when);
//   fixed4    automatic steps, the paper's 4 projections per step;
//   defaults  automatic steps and adaptive projections (what a user gets).
// Reported: ms per step, per frame and per simulated second, steps and projections per frame,
// and the physics of every frame (mean and max compression, max speed; in the CSV also the
// front, the 99.9th and 99.99th percentiles of speed and the fluid's centre height). The first frame is the
// warm-up (graph capture, first allocations) and is not timed. CUDA frames are timed with events
// on the stepper's stream, CPU frames with the steady clock; both include the per-step host read
// of the fastest particle that automatic steps need.
#pragma once

#include "Scene.h"
#include "ToolOptions.h"

#include <cstdint>
#include <string>
#include <vector>

namespace pbf
{

struct RefinedRun
{
  std::string mode;
  double spacing = 0;
  std::size_t particles = 0;
  int frames = 0;
  std::uint64_t timedSteps = 0;  // frames 2..N
  long timedIterations = 0;      // frames 2..N
  std::vector<double> frameMs;   // frames 2..N
  double worstAverage = 0, worstMax = 0, fastest = 0; // every frame
  double minTimeStep = 0, maxTimeStep = 0;
  double reachedTime = 0;
  std::string failure; // empty: the run reached the end
  bool diverged = false;
};

struct RefinedSettings
{
  std::vector<double> spacings;
  std::vector<std::string> modes; // of "fixed", "fixed4", "defaults"
  double until = 2.0;
  double frameInterval = 1.0 / 60.0;
  std::string csvDirectory; // empty: no CSV
};

RefinedSettings refinedSettings(const ToolOptions& options);

// One run; a failure (divergence included) is recorded in the result, never thrown.
RefinedRun runRefined(const ToolOptions& options, const Scene& scene, double spacing,
  const std::string& mode, const RefinedSettings& settings);

// Prints the table; returns false when a fixed4 or defaults run failed (a fixed-step divergence
// is a result, not a failure of the tool).
bool printRefinedTable(const std::vector<RefinedRun>& runs, double frameInterval);

} // namespace pbf
