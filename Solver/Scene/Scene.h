// Where the fluid is: the domain box, fluid regions filled on a cubic lattice, and emitters.
// How it behaves (spacing, solver, time step) is Parameters. Scenes are JSON; Data/README.md has
// the schema, and the shipped scenes in Data/ are compiled in as presets.
#pragma once

#include "Parameters.h"
#include "Solids.h"
#include "Particles.h"
#include "Vec3.h"

#include <functional>
#include <string>
#include <vector>

namespace pbf
{

// `liquid` is an index into Scene::liquids (0 where the scene names none).
struct FluidBox
{
  Vec3d min, max;
  Vec3d velocity{ 0, 0, 0 };
  int liquid = 0;
};

struct FluidSphere
{
  Vec3d center;
  double radius = 0;
  Vec3d velocity{ 0, 0, 0 };
  int liquid = 0;
};

// A nozzle that adds a disk of particles, one lattice layer at a time, while start <= t < stop.
// The file gives its speed, or its volume rate (an inflow's target): Simulation then sets the
// speed that releases exactly that volume as whole layers at the run's spacing (emitterSpeed).
struct Emitter
{
  Vec3d center;
  Vec3d direction{ 1, 0, 0 }; // normalised on load
  double radius = 0;
  double speed = 0; // [m/s]; 0 while `rate` is still to be resolved
  double start = 0;
  double stop = 0;
  int liquid = 0;
  double rate = 0;  // [m^3/s]; 0: the file gave the speed
};

// Where particles leave the simulation (Physics/Outflow.h): a face of the domain, as the slab
// `depth` deep inside it, or a box. A face's slab spans the whole face.
struct Outflow
{
  int face = -1;     // -1: a box; 0-5: the domain's -x, +x, -y, +y, -z, +z face
  double depth = 0;  // [m], a face's; 0: one smoothing length (the wall's reach is gone with it)
  Box box;           // a box's
};

struct Scene
{
  std::string name;
  std::string description;
  Box domain;
  // "liquids": several liquids by name (Parameters::liquids); empty: one, of the parameters.
  std::vector<Liquid> liquids;
  std::vector<FluidBox> boxes;
  std::vector<FluidSphere> spheres;
  std::vector<Emitter> emitters;
  std::vector<Outflow> outflows;
  std::vector<SolidRegion> solids; // "obstacles": what the fluid flows around
};

// Throws InvalidInput naming the key path and value ("fluid[1].radius = -2: must be > 0") for
// malformed JSON, unknown keys, missing keys, wrong types and bad values.
Scene parseScene(const std::string& json);
Scene loadSceneFile(const std::string& path);

// The scenes shipped in Data/, compiled in. Names are the file names without ".json".
std::vector<std::string> presetNames();
Scene presetScene(const std::string& name); // throws InvalidInput for an unknown name

// Upper bound on particles a scene may make, initial and emitted: 32-bit indices with headroom.
constexpr std::size_t kMaxParticles = std::size_t(1) << 31;

// An upper estimate of the particles the scene makes at the parameters' spacing, emitters included,
// computed without making them.
double estimateParticleCount(const Scene& scene, const Parameters& parameters);

// site(x, v, liquid) for every lattice site of the scene's boxes, then of its spheres, at spacing
// s, in fillScene's order. A scene without liquids gives liquid 0.
void forEachSceneSite(const Scene& scene, double s,
  const std::function<void(const Vec3d&, const Vec3d&, std::uint8_t)>& site);

// Throws InvalidInput when the spacing would make more than kMaxParticles of the scene.
void checkSceneSize(const Scene& scene, const Parameters& parameters);

// The initial particles of a scene at the parameters' spacing, ids 0..N-1. Throws InvalidInput
// before allocating when the spacing would make more than kMaxParticles.
ParticleBatch fillScene(const Scene& scene, const Parameters& parameters);

// The lattice sites of an emitter's disk at spacing s: the particles of one layer.
long emitterSites(const Emitter& emitter, double s);
// The emitter's speed at the parameters' spacing: the file's, or rate / (sites s^2), so that the
// whole layers released carry exactly `rate` m^3/s.
double emitterSpeed(const Emitter& emitter, const Parameters& parameters);

// The outflows as boxes at the parameters' spacing and smoothing length. A face's slab reaches
// one spacing beyond the domain on every side, as far as particles may stray (checkBatch).
std::vector<Box> outflowZones(const Scene& scene, const Parameters& parameters);

// The name errors give outflow k: "outflows[k] (face +x)" or "outflows[k] (box)".
std::string outflowName(const Scene& scene, std::size_t k);

// Parameters with the scene's domain and liquids.
Parameters withSceneDomain(Parameters parameters, const Scene& scene);

} // namespace pbf
