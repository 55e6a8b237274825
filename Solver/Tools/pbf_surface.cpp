// pbf_surface: the fluid's surface of a scene's frame after --until seconds on --backend,
// extracted on this machine's CPU with all its threads (Surface/SurfaceExtraction.h) and, when
// the backend is cuda, on the GPU from the stepper's own device arrays (Cuda/CudaSurface.h), in
// the same run on the same frame: median milliseconds of each (the GPU's from CUDA events: the
// mesh made on the device, then its copy to the host), triangles, working memory per particle,
// and whether the two meshes are the same bits. The GPU surface's benchmark against the 16-core
// CPU, and the bytes per particle at 1M and 10M:
//   pbf_surface --backend cuda --scene dam_break --spacing 0.005 --until 0.2
#include "Scene.h"
#include "Simulation.h"
#include "SurfaceExtraction.h"
#include "ToolOptions.h"

#ifdef PBF_WITH_CUDA
#include "Cuda/CudaBackend.h"
#include "Cuda/CudaSurface.h"
#endif

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace pbf;

#ifdef PBF_WITH_CUDA
struct GpuSurfaceTimes
{
  double extractMs = 0, downloadMs = 0, hostMs = 0, bytes = 0;
  bool identical = false; // the same mesh as the CPU's, to the bit, from either source
};

// The GPU surface of the same frame: from the stepper's device arrays (extraction and download
// times, medians of `repeat`) and from the host's arrays as the filter does (wall time, median of
// up to 5), and whether both are the CPU's mesh.
GpuSurfaceTimes timeGpuSurface(const cuda::CudaStepperInterface& gpu, const Parameters& parameters,
  const Snapshot<float>& state, const SurfaceOptions& surface, long repeat, const SurfaceMesh& mesh)
{
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  if (gpu.precision() != Precision::Single)
  {
    throw InvalidInput("pbf_surface: the GPU comparison reads single precision; drop --precision");
  }
  const auto at = gpu.deviceState();
  cuda::DeviceParticles<float> device;
  device.x = static_cast<const Vec3<float>*>(at.x);
  device.v = static_cast<const Vec3<float>*>(at.v);
  device.rho = static_cast<const float*>(at.density);
  device.n = at.n;
  cuda::SurfaceExtractor extractor;
  SurfaceMesh onDevice = extractor.extract(device, parameters, surface, gpu.stream());
  std::vector<double> extract, download, host;
  bool sameSizes = true;
  for (long k = 0; k < repeat; ++k)
  {
    onDevice = extractor.extract(device, parameters, surface, gpu.stream());
    extract.push_back(extractor.lastTimes().extractMs);
    download.push_back(extractor.lastTimes().downloadMs);
  }
  // From the host's arrays, as the filter does: upload, extract, download, wall time.
  for (long k = 0; k < std::min<long>(repeat, 5); ++k)
  {
    const auto start = std::chrono::steady_clock::now();
    const SurfaceMesh fromHost = extractor.extract<float>(state.position.data(),
      state.velocity.data(), state.density.data(), state.position.size(),
      parameters, surface);
    host.push_back(std::chrono::duration<double, std::milli>(
      std::chrono::steady_clock::now() - start).count());
    sameSizes = sameSizes && fromHost.triangles.size() == onDevice.triangles.size();
  }
  GpuSurfaceTimes t;
  t.extractMs = median(extract);
  t.downloadMs = median(download);
  t.hostMs = median(host);
  t.bytes = static_cast<double>(extractor.deviceBytes());
  auto same = [](const auto& a, const auto& b) {
    return a.size() == b.size() &&
      (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
  };
  const bool equal = same(onDevice.points, mesh.points) && same(onDevice.normals, mesh.normals) &&
    same(onDevice.velocity, mesh.velocity) && same(onDevice.density, mesh.density) &&
    same(onDevice.triangles, mesh.triangles);
  t.identical = sameSizes && equal;
  return t;
}
#endif

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "until", "simulated time before the surface is taken [s] (default 0.2)" },
    { "repeat", "GPU extractions timed (default 20, after one untimed)" },
    { "cpu-repeat", "CPU extractions timed (default 3)" },
    { "resolution", "SurfaceResolution: node spacing in particle spacings (default 0.5)" },
    { "anisotropic", "1: anisotropic kernels (SurfaceAnisotropic; default 0)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const double until = toolReal(options, "until", 0.2);
    const long repeat = toolInteger(options, "repeat", 20, 1);
    const long cpuRepeat = toolInteger(options, "cpu-repeat", 3, 1);
    SurfaceOptions surface;
    surface.resolution = toolReal(options, "resolution", surface.resolution);
    surface.anisotropic = toolInteger(options, "anisotropic", 0, 0) != 0;
    const Scene scene = toolScene(options);
    Simulation simulation(scene, options.parameters, options.backend, options.precision);
    const auto run0 = std::chrono::steady_clock::now();
    simulation.advanceTo(until);
    const double runSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - run0).count();
    Snapshot<float> state;
    simulation.stepper().read(state);
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v.empty() ? 0.0 : v[v.size() / 2];
    };
    std::vector<double> cpuMs;
    SurfaceMesh mesh;
    for (long k = 0; k < cpuRepeat; ++k)
    {
      const auto start = std::chrono::steady_clock::now();
      mesh = extractSurface<float>(state.position.data(), state.velocity.data(),
        state.density.data(), state.position.size(), simulation.parameters(), surface, true);
      cpuMs.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    int threads = 1;
#ifdef _OPENMP
    threads = omp_get_max_threads();
#endif
    const double n = static_cast<double>(state.position.size());
    std::printf("particles,threads,simulated_s,run_s,cpu_ms,gpu_extract_ms,gpu_download_ms,"
                "gpu_host_arrays_ms,cpu_over_gpu,triangles,vertices,blocks_sampled,blocks_kept,"
                "cpu_bytes_per_particle,gpu_bytes_per_particle,identical\n");
    double extractMs = 0, downloadMs = 0, hostMs = 0, gpuBytes = 0;
    std::string identical = "-";
#ifdef PBF_WITH_CUDA
    if (const auto* gpu = dynamic_cast<const cuda::CudaStepperInterface*>(&simulation.stepper()))
    {
      const GpuSurfaceTimes t = timeGpuSurface(*gpu, simulation.parameters(), state, surface,
        repeat, mesh);
      extractMs = t.extractMs;
      downloadMs = t.downloadMs;
      hostMs = t.hostMs;
      gpuBytes = t.bytes / n;
      identical = t.identical ? "yes" : "no";
    }
#endif
    const double cpu = median(cpuMs);
    std::printf("%zu,%d,%g,%.1f,%.1f,%.3f,%.3f,%.2f,%.0f,%zu,%zu,%zu,%zu,%.0f,%.0f,%s\n",
      state.position.size(), threads, until, runSeconds, cpu, extractMs, downloadMs, hostMs,
      extractMs > 0 ? cpu / extractMs : 0.0, mesh.triangles.size(), mesh.points.size(),
      mesh.sampledBlocks, mesh.keptBlocks, static_cast<double>(mesh.peakBytes) / n, gpuBytes,
      identical.c_str());
    return 0;
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_surface: " << error.what() << "\n";
    return 1;
  }
}
