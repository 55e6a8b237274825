// pbf_surface: the fluid's surface (Surface/SurfaceExtraction.h) of a scene after --until
// seconds on --backend, extracted on this machine's CPU with all its threads --repeat times:
// the median milliseconds, the triangles and the working memory per particle. The 16-core
// baseline the GPU surface is measured against, and the bytes per particle at 1M and 10M:
//   pbf_surface --backend cuda --scene dam_break --spacing 0.005 --until 0.2
#include "Scene.h"
#include "Simulation.h"
#include "SurfaceExtraction.h"
#include "ToolOptions.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace pbf;

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "until", "simulated time before the surface is taken [s] (default 0.2)" },
    { "repeat", "extractions timed (default 3)" },
    { "resolution", "SurfaceResolution: node spacing in particle spacings (default 0.5)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const double until = toolReal(options, "until", 0.2);
    const long repeat = toolInteger(options, "repeat", 3, 1);
    SurfaceOptions surface;
    surface.resolution = toolReal(options, "resolution", surface.resolution);
    const Scene scene = toolScene(options);
    Simulation simulation(scene, options.parameters, options.backend, options.precision);
    const auto run0 = std::chrono::steady_clock::now();
    simulation.advanceTo(until);
    const double runSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - run0).count();
    Snapshot<float> state;
    simulation.stepper().read(state);
    std::vector<double> ms;
    SurfaceMesh mesh;
    for (long k = 0; k < repeat; ++k)
    {
      const auto start = std::chrono::steady_clock::now();
      mesh = extractSurface<float>(state.position.data(), state.velocity.data(),
        state.density.data(), state.position.size(), simulation.parameters(), surface, true);
      ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(ms.begin(), ms.end());
    int threads = 1;
#ifdef _OPENMP
    threads = omp_get_max_threads();
#endif
    const double n = static_cast<double>(state.position.size());
    std::printf("particles,threads,simulated_s,run_s,surface_ms_median,triangles,vertices,"
                "blocks_sampled,blocks_kept,bytes_per_particle\n");
    std::printf("%zu,%d,%g,%.1f,%.1f,%zu,%zu,%zu,%zu,%.0f\n", state.position.size(), threads,
      until, runSeconds, ms[ms.size() / 2], mesh.triangles.size(), mesh.points.size(),
      mesh.sampledBlocks, mesh.keptBlocks, static_cast<double>(mesh.peakBytes) / n);
    return 0;
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_surface: " << error.what() << "\n";
    return 1;
  }
}
