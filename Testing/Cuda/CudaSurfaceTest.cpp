// The GPU surface (Cuda/CudaSurface.h) against the CPU's (Surface/SurfaceExtraction.h), label
// "gpu": the same mesh bit for bit, from host arrays and from a CUDA stepper's own device arrays;
// two extractions alike; bad input refused with the field named. SKIPPED without a device.
//
// Tolerance: none. Both run SurfaceCells.h's one definition in double, the GPU without fused
// multiply-adds, the particles summed in the same order (by cell, by position within a cell), so
// every value must round alike; a difference is a bug, not rounding.
#include "Cuda/CudaBackend.h"
#include "Cuda/CudaSurface.h"
#include "RequireGpu.h"
#include "Scene.h"
#include "SignedDistance.h"
#include "Simulation.h"
#include "Solids.h"
#include "SurfaceExtraction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

using namespace pbf;

namespace
{

// A sphere of fluid of 12 spacings' radius, moving, with a density that varies so that the
// interpolated fields are tested too.
template <class Real>
struct Particles
{
  Parameters parameters;
  std::vector<Vec3<Real>> x, v;
  std::vector<Real> rho;
};

// jitter: each particle moved by up to a fifth of a spacing (a deterministic pattern), so that
// the anisotropic kernels take every shape.
template <class Real>
Particles<Real> sphere(bool jitter = false)
{
  Particles<Real> s;
  s.parameters.particleSpacing = 0.02;
  Scene scene;
  scene.domain = { { 0, 0, 0 }, { 1, 1, 1 } };
  scene.spheres.push_back({ { 0.5, 0.45, 0.55 }, 0.24, { 1, -2, 0.5 } });
  s.parameters.domain = scene.domain;
  const ParticleBatch batch = fillScene(scene, s.parameters);
  for (std::size_t i = 0; i < batch.position.size(); ++i)
  {
    const double k = static_cast<double>(i);
    const Vec3d moved = jitter
      ? batch.position[i] + Vec3d{ std::sin(1.3 * k), std::sin(2.1 * k), std::sin(3.7 * k) } * 0.004
      : batch.position[i];
    s.x.push_back(Vec3<Real>::from(moved));
    s.v.push_back(Vec3<Real>::from(batch.velocity[i]));
    s.rho.push_back(static_cast<Real>(1000 + 10 * std::sin(static_cast<double>(i))));
  }
  return s;
}

void expectSameMesh(const SurfaceMesh& gpu, const SurfaceMesh& cpu)
{
  ASSERT_EQ(gpu.points.size(), cpu.points.size());
  ASSERT_EQ(gpu.triangles.size(), cpu.triangles.size());
  ASSERT_EQ(gpu.velocity.size(), cpu.velocity.size());
  ASSERT_EQ(gpu.density.size(), cpu.density.size());
  EXPECT_GT(cpu.triangles.size(), 100u);
  auto same = [](const auto& a, const auto& b) {
    return a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
  };
  EXPECT_TRUE(same(gpu.points, cpu.points));
  EXPECT_TRUE(same(gpu.normals, cpu.normals));
  EXPECT_TRUE(same(gpu.velocity, cpu.velocity));
  EXPECT_TRUE(same(gpu.density, cpu.density));
  EXPECT_TRUE(same(gpu.triangles, cpu.triangles));
  EXPECT_EQ(gpu.sampledBlocks, cpu.sampledBlocks);
  EXPECT_EQ(gpu.keptBlocks, cpu.keptBlocks);
  // Where they differ, the first difference and how many, to tell a wrong vertex from rounding.
  auto first = [](const char* what, const std::vector<Vec3<float>>& a, const std::vector<Vec3<float>>& b) {
    std::size_t count = 0, at = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
    {
      if (std::memcmp(&a[i], &b[i], sizeof(a[i])) != 0 && count++ == 0)
      {
        at = i;
      }
    }
    if (count > 0)
    {
      ADD_FAILURE() << count << " " << what << " differ; the first, " << at << ": GPU ("
                    << std::hexfloat << a[at].x << ", " << a[at].y << ", " << a[at].z << "), CPU ("
                    << b[at].x << ", " << b[at].y << ", " << b[at].z << ")";
    }
  };
  first("points", gpu.points, cpu.points);
  first("normals", gpu.normals, cpu.normals);
}

template <class Real>
void expectCpuMesh(const SurfaceOptions& options, const SurfaceSolids& solids = {}, bool jitter = false)
{
  const Particles<Real> s = sphere<Real>(jitter);
  cuda::SurfaceExtractor extractor;
  const SurfaceMesh gpu = extractor.extract<Real>(s.x.data(), s.v.data(), s.rho.data(), s.x.size(),
    s.parameters, options, solids);
  const SurfaceMesh cpu = extractSurface<Real>(s.x.data(), s.v.data(), s.rho.data(), s.x.size(),
    s.parameters, options, true, {}, solids);
  expectSameMesh(gpu, cpu);
  // Again on the same extractor (its arrays reused): the same bits.
  expectSameMesh(extractor.extract<Real>(s.x.data(), s.v.data(), s.rho.data(), s.x.size(),
                   s.parameters, options, solids),
    cpu);
}

} // namespace

TEST(CudaSurface, TheGpuGivesTheCpuMeshBitForBit)
{
  PBF_REQUIRE_GPU();
  expectCpuMesh<double>(SurfaceOptions{});
  expectCpuMesh<float>(SurfaceOptions{});
  // A finer grid, another level, and smoothing (the neighbours' sums in index order).
  SurfaceOptions other;
  other.resolution = 0.35;
  other.isoValue = 0.3;
  other.smoothing = 3;
  expectCpuMesh<float>(other);
  // A coarse grid, where a block is narrower than 2 h and a particle reaches many blocks.
  SurfaceOptions coarse;
  coarse.resolution = 0.2;
  expectCpuMesh<double>(coarse);
  // Anisotropic kernels: the shapes (Jacobi rotations, cube roots), the second sort by centre.
  SurfaceOptions anisotropic;
  anisotropic.anisotropic = true;
  expectCpuMesh<float>(anisotropic);
  expectCpuMesh<float>(anisotropic, {}, true);
  anisotropic.smoothing = 1;
  expectCpuMesh<double>(anisotropic, {}, true);
}

TEST(CudaSurface, ObstaclesClipAsOnTheCpu)
{
  PBF_REQUIRE_GPU();
  // A slab through the sphere's lower part, standing, and a ball turned and moved by a pose (the
  // rotated lookup of a moving solid).
  const Particles<float> s = sphere<float>();
  SolidRegion slab, ball;
  slab.box = { { 0.1, 0.1, 0.1 }, { 0.9, 0.9, 0.4 } };
  ball.kind = SolidRegion::Kind::Sphere;
  ball.center = { 0.6, 0.5, 0.7 };
  ball.radius = 0.1;
  const std::vector<DistanceGrid> fields = solidFields({ slab, ball }, s.parameters);
  SolidMotion motion;
  motion.pivot = ball.center;
  Keyframe start, end;
  end.time = 1;
  end.translation = { -0.05, 0.02, 0 };
  end.rotation = Rotation::fromDegrees({ 10, 20, 30 });
  motion.keyframes = { start, end };
  SurfaceSolids solids;
  solids.views.push_back(fields[0].view<double>(fields[0].phi.data(), nullptr));
  solids.views.push_back(placed(fields[1].view<double>(fields[1].phi.data(), nullptr), motion.at(0.5)));
  SurfaceOptions smoothed;
  smoothed.smoothing = 2;
  expectCpuMesh<float>(SurfaceOptions{}, solids);
  expectCpuMesh<float>(smoothed, solids);
}

TEST(CudaSurface, AStepperFrameOnTheDeviceGivesTheCpuMesh)
{
  PBF_REQUIRE_GPU();
  // The dam break after its column has started to fall, on the device from the stepper's own
  // arrays (its order, not the read-back one), against the CPU on the read-back frame.
  const Scene scene = presetScene("dam_break");
  Parameters p;
  p.particleSpacing = 0.03;
  p = withSceneDomain(p, scene);
  auto stepper = cuda::makeCudaStepper(Precision::Single, p, fillScene(scene, p), cuda::Options{});
  for (int s = 0; s < 40; ++s)
  {
    stepper->step();
  }
  Snapshot<float> frame;
  stepper->read(frame);
  const auto state = stepper->deviceState();
  ASSERT_EQ(state.n, frame.position.size());
  cuda::DeviceParticles<float> device;
  device.x = static_cast<const Vec3<float>*>(state.x);
  device.v = static_cast<const Vec3<float>*>(state.v);
  device.rho = static_cast<const float*>(state.density);
  device.n = state.n;
  SurfaceOptions options;
  options.smoothing = 2;
  cuda::SurfaceExtractor extractor;
  const SurfaceMesh gpu = extractor.extract(device, p, options, stepper->stream());
  const SurfaceMesh cpu = extractSurface<float>(frame.position.data(), frame.velocity.data(),
    frame.density.data(), frame.position.size(), p, options, true);
  expectSameMesh(gpu, cpu);
  EXPECT_GT(extractor.lastTimes().extractMs, 0.0);
  EXPECT_GT(extractor.deviceBytes(), 0u);
}

TEST(CudaSurface, BadInputIsRefusedWithTheFieldNamed)
{
  PBF_REQUIRE_GPU();
  Particles<float> s = sphere<float>();
  cuda::SurfaceExtractor extractor;
  // No particles: an empty mesh.
  EXPECT_TRUE(extractor.extract<float>(nullptr, nullptr, nullptr, 0, s.parameters, {}).triangles.empty());
  // A non-finite position names its particle, as the CPU does.
  s.x[7].y = std::numeric_limits<float>::quiet_NaN();
  try
  {
    extractor.extract<float>(s.x.data(), s.v.data(), s.rho.data(), s.x.size(), s.parameters, {});
    FAIL() << "a NaN position was accepted";
  }
  catch (const InvalidInput& e)
  {
    EXPECT_NE(std::string(e.what()).find("particle 7 has a non-finite position"), std::string::npos)
      << e.what();
  }
  s.x[7].y = 0.5f;
  SurfaceOptions bad;
  bad.resolution = -1;
  try
  {
    extractor.extract<float>(s.x.data(), s.v.data(), s.rho.data(), s.x.size(), s.parameters, bad);
    FAIL() << "SurfaceResolution -1 was accepted";
  }
  catch (const InvalidInput& e)
  {
    EXPECT_NE(std::string(e.what()).find("SurfaceResolution = -1"), std::string::npos) << e.what();
  }
  // The extractor still works after refusing.
  EXPECT_GT(extractor.extract<float>(s.x.data(), s.v.data(), s.rho.data(), s.x.size(),
              s.parameters, {}).triangles.size(), 100u);
}
