// Small scenes and helpers shared by the solver tests.
#pragma once

#include "Scene.h"
#include "Simulation.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <string>
#include <vector>

namespace pbf::test
{

// A preset scene at the given particle spacing: its parameters (domain from the scene) and the
// particles that fill it, as every rank of a decomposed run is handed them.
struct PresetFluid
{
  Parameters parameters;
  ParticleBatch fluid;
};
PresetFluid presetFluid(const std::string& name, double spacing);
// The same for any scene (its emitters aside: they add particles through Simulation).
PresetFluid sceneFluid(const Scene& scene, double spacing);

// The divergence tests' settings: s = 0.05 m with fixed steps (the default 1/240 s), the paper's
// 4 projections and light XSPH, which the blow-ups need (automatic steps and adaptive projections
// prevent them).
Parameters coarseFixedSteps();
// The same with steps of 0.05 s, 12 times the default: the dam break piles up on the floor at
// 3 x rho_0 by the third step, on every backend.
Parameters hugeFixedStep();

// A block of fluid filling the floor of a closed box: side x side x side lattice sites.
Scene restingBlock(int side, double spacing);

// Sum of m g (height) over the particles: the potential energy above the floor [J].
double potentialEnergy(const Simulation& simulation);

// Snapshot rows keyed by particle id, for comparisons across backends whose order may differ.
std::map<std::int64_t, std::size_t> indexById(const Snapshot<double>& snapshot);

// Largest |x_a - x_b| / |x_b| over particles matched by id (infinity for a NaN). Adds a gtest
// failure for a count that differs, an id twice in a, or an id of a missing from b.
double maxRelativePositionError(const Snapshot<double>& a, const Snapshot<double>& b);

// Largest |p_a - p_b| over particles matched by id, over b's largest |p| (the pressure's scale:
// a particle's own pressure may be 0). Infinity for a NaN or a particle missing from b.
double maxRelativePressureError(const Snapshot<double>& a, const Snapshot<double>& b);

// Each particle's liquid by its id.
std::map<std::int64_t, int> liquidsById(const Snapshot<double>& snapshot);

// The ranks' states one after the other, as one state (a decomposed run's particles).
Snapshot<double> joined(const std::vector<Snapshot<double>>& parts);

// Two states equal bit for bit, in the same order (two backends that sort alike).
template <class Real>
void expectBitIdentical(const Snapshot<Real>& a, const Snapshot<Real>& b)
{
  ASSERT_EQ(a.id, b.id);
  const std::size_t n = a.id.size();
  EXPECT_EQ(std::memcmp(a.position.data(), b.position.data(), n * sizeof(a.position[0])), 0);
  EXPECT_EQ(std::memcmp(a.velocity.data(), b.velocity.data(), n * sizeof(a.velocity[0])), 0);
  EXPECT_EQ(std::memcmp(a.density.data(), b.density.data(), n * sizeof(a.density[0])), 0);
  EXPECT_EQ(std::memcmp(a.lambda.data(), b.lambda.data(), n * sizeof(a.lambda[0])), 0);
  EXPECT_EQ(std::memcmp(a.pressure.data(), b.pressure.data(), n * sizeof(a.pressure[0])), 0);
}

// Two liquids that move: a water column (1000 kg/m^3) breaking onto a pool of oil (800, its own
// XSPH alpha of 0.05), and a nozzle that adds oil from 0.1 s to 0.3 s.
Scene twoLiquids();

// Water (1000 kg/m^3) and oil (800, its own XSPH alpha of 0.05) side by side along x, both
// released at once: the water runs under the oil across the interface, which a decomposition
// along x cuts through.
Scene sideBySideLiquids();

// The dam break with a box solid cutting into the column (its fluid removed, the rest touching
// it from the first step) and a sphere in the surge's way.
Scene damBreakWithSolids();

// A unit icosahedron subdivided `levels` times and pushed onto the sphere of `radius` about c,
// its triangles facing out.
TriangleMesh icosphere(const Vec3d& c, double radius, int levels);
// The closed box b as 12 triangles facing out.
TriangleMesh boxMesh(const Box& b);

} // namespace pbf::test
