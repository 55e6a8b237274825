// Algorithm 1 of Macklin & Mueller 2013 as control flow, written once for every backend: which
// stage runs when, how many projections run and when the solve stops, where s_corr's tensile
// term and Chebyshev's acceleration apply. Each backend runs runStep over a Loop of its own that
// says how a stage runs there:
// - Cpu/HostStepLoop.h: the serial and OpenMP stepper, and one rank's CPU sub-domain (whose
//   ghost exchanges are its refreshes between the stages);
// - Cuda/DeviceStepLoop.h: the CUDA stepper, queued as kernels (one captured graph a step, the
//   adaptive stop as conditional nodes);
// - Cuda/DeviceSubdomainSolve.h: one rank's GPU sub-domain (border and interior launches, the
//   refreshes beside the interior's).
// A new stage is added here, and to each Loop.
//
// Loop interface:
//   predict()                 lines 1-4: forces and the predicted positions x*
//   findNeighbours()          lines 5-7: the cell sort of x* (a decomposed stepper first moves the
//                             particles to their slab's owner and receives its ghosts)
//   densityAndLambda(p)       lines 9-11 for projection p; every stage leaves the fields it wrote
//                             up to date on the ghosts too
//   measureCompression(p, mayStop)   adaptive mode: the whole fluid's compression after the
//                             density pass; with mayStop, a compression within the tolerance ends
//                             the solve: nothing more of this projection or a later one runs
//   sumLoads(p)               what the fluid pushes each solid with in projection p (the solid's
//                             share of delta p, SolidTerms.h's solidLoads), added to the step's
//                             loads; nothing once the solve has stopped
//   correct(p)                lines 12-18: delta p (eq. 12 with s_corr when p.tensile) and the
//                             Jacobi update, blended when p.accelerate; a Loop may also run line 21
//                             in the correction where p.last says no projection follows
//   whileCompressed(first, end, body)   body(loop, k) for k = first, ... < end, until the solve
//                             has stopped; loop is this Loop or one standing for it (the CUDA
//                             stepper's captures each body into a conditional node)
//   finishSolve()             line 21 for the particles whose correction did not run it
//   vorticityAndXsph()        the sums of line 22: omega (eq. 15) and XSPH's (eq. 17)
//   confine()                 line 22: the velocity with confinement (eq. 16) and XSPH
//   commit()                  line 23: x = x*
#pragma once

#include "Chebyshev.h"
#include "Parameters.h"

namespace pbf
{

// One projection of the solve (Algorithm 1, lines 9-18).
struct Projection
{
  int iteration = 0;       // k, from 0
  bool tensile = false;    // s_corr's push (eq. 13), in the first projection of a step only
  bool accelerate = false; // Chebyshev's blend with x* two projections back (from k = 1)
  double omega = 1.0;      // the blend's weight (Chebyshev.h)
  bool last = false;       // the count allows no projection after this one
};

// How a step's solve runs: its projections and its stop.
struct SolveRule
{
  int iterations = 1;        // the count, or in adaptive mode the most a step may run
  bool adaptive = false;     // stop once the compression is within the tolerance
  double chebyshevRho = 0.0; // Chebyshev's acceleration; 0: plain Jacobi

  static SolveRule of(const Parameters& parameters)
  {
    SolveRule rule;
    rule.iterations = parameters.solverIterations;
    rule.adaptive = parameters.densityErrorTolerance > 0;
    rule.chebyshevRho = parameters.chebyshevRho;
    return rule;
  }

  Projection projection(int k) const
  {
    Projection p;
    p.iteration = k;
    p.tensile = k == 0;
    p.accelerate = chebyshevRho > 0 && k > 0;
    p.omega = chebyshevWeight(chebyshevRho, k);
    p.last = k + 1 == iterations;
    return p;
  }
};

// One step.
template <class Loop>
void runStep(Loop& loop, const SolveRule& rule)
{
  loop.predict();
  // Neighbours are found once per step, on the predicted positions.
  loop.findNeighbours();
  const auto projection = [&rule](auto& at, int k) {
    const Projection p = rule.projection(k);
    at.densityAndLambda(p);
    if (rule.adaptive)
    {
      // The first projection always runs: it carries the step's tensile push.
      at.measureCompression(p, k > 0);
    }
    at.sumLoads(p);
    at.correct(p);
  };
  projection(loop, 0);
  loop.whileCompressed(1, rule.iterations, projection);
  loop.finishSolve();
  loop.vorticityAndXsph();
  loop.confine();
  loop.commit();
}

} // namespace pbf
