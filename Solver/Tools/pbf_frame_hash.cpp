// pbf_frame_hash: a fingerprint of a scene's frames on one backend, to show that a change keeps
// every frame bit for bit: run it before and after and compare the lines. Each frame's hash is
// over every particle's id, position and velocity bits, combined so that neither the particles'
// order nor the rank that holds them changes it (a decomposed run hashes like one rank when its
// particles are the same). --ranks N decomposes the run over N threads (the CPU or the GPU
// sub-domain stepper, by --backend).
#include "Scene.h"
#include "Simulation.h"
#include "Distributed/ThreadCluster.h"
#include "ToolOptions.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <mutex>
#include <vector>

using namespace pbf;

namespace
{

// FNV-1a over the bytes of one value, from `h`.
template <class T>
std::uint64_t fnv1a(std::uint64_t h, const T& value)
{
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (unsigned char b : bytes)
  {
    h = (h ^ b) * 0x100000001b3ull;
  }
  return h;
}

// One particle's hash. The positions and velocities are read as doubles, which holds a float's
// bits exactly, so the same function serves both precisions.
std::uint64_t particleHash(std::int64_t id, const Vec3d& x, const Vec3d& v)
{
  std::uint64_t h = fnv1a(0xcbf29ce484222325ull, id);
  for (double c : { x.x, x.y, x.z, v.x, v.y, v.z })
  {
    h = fnv1a(h, c);
  }
  return h;
}

// The frame's hash is the sum of the particles' (mod 2^64): the same in any order, on any ranks.
struct FrameHash
{
  std::uint64_t sum = 0;
  std::size_t particles = 0;
};

std::vector<FrameHash> hashFrames(const ToolOptions& options, const Scene& scene, int ranks,
  int frames, double frame)
{
  std::vector<FrameHash> hashes(static_cast<std::size_t>(frames) + 1);
  std::mutex mutex;
  auto run = [&](distributed::Communicator* communicator) {
    Simulation simulation(scene, options.parameters, options.backend, options.precision,
      communicator);
    for (int f = 0; f <= frames; ++f)
    {
      simulation.advanceTo(f * frame);
      Snapshot<double> state;
      simulation.stepper().read(state);
      std::uint64_t sum = 0;
      for (std::size_t i = 0; i < state.position.size(); ++i)
      {
        sum += particleHash(state.id[i], state.position[i], state.velocity[i]);
      }
      std::lock_guard<std::mutex> lock(mutex);
      hashes[static_cast<std::size_t>(f)].sum += sum;
      hashes[static_cast<std::size_t>(f)].particles += state.position.size();
    }
  };
  if (ranks > 1)
  {
    distributed::runThreadCluster(ranks, [&](distributed::Communicator& c) { run(&c); });
  }
  else
  {
    run(nullptr);
  }
  return hashes;
}

} // namespace

int main(int argc, char** argv)
{
  const std::map<std::string, std::string> keys = {
    { "ranks", "decompose over this many ranks (threads; default 1)" },
    { "frames", "frames to hash after frame 0 (default 10)" },
    { "frame", "the frame interval [s] (default 0.05)" },
  };
  try
  {
    ToolOptions options = parseToolOptions(argc, argv, keys);
    const Scene scene = toolScene(options);
    const long ranks = toolInteger(options, "ranks", 1, 1);
    const long frames = toolInteger(options, "frames", 10, 1);
    const double frame = toolReal(options, "frame", 0.05);
    const std::vector<FrameHash> hashes =
      hashFrames(options, scene, static_cast<int>(ranks), static_cast<int>(frames), frame);
    std::uint64_t all = 0xcbf29ce484222325ull;
    for (std::size_t f = 0; f < hashes.size(); ++f)
    {
      std::printf("%s,%s,%s,%ld,%zu,%.4f,%zu,%016llx\n", scene.name.c_str(),
        toString(options.backend), toString(options.precision), ranks, f, double(f) * frame,
        hashes[f].particles, static_cast<unsigned long long>(hashes[f].sum));
      all = fnv1a(all, hashes[f].sum);
    }
    std::printf("%s,%s,%s,%ld,all,,,%016llx\n", scene.name.c_str(), toString(options.backend),
      toString(options.precision), ranks, static_cast<unsigned long long>(all));
    return 0;
  }
  catch (const std::exception& error)
  {
    std::cerr << "pbf_frame_hash: " << error.what() << "\n";
    return 1;
  }
}
