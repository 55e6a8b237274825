// Command-line options shared by the solver's tools: "--key value" pairs mapped onto Parameters,
// the backend and the precision. No VTK, no third-party parser: the GPU machine has neither.
#pragma once

#include "Parameters.h"
#include "Scene.h"
#include "Stepper.h"

#include <map>
#include <set>
#include <vector>
#include <string>

namespace pbf
{

struct ToolOptions
{
  std::string scene = "dam_break"; // a preset name or a path to a .json file
  Parameters parameters;
  Backend backend = Backend::Serial;
  Precision precision = Precision::Single;
  std::map<std::string, std::string> extra; // tool-specific keys
  std::set<std::string> given;               // every key on the command line
};

// The kernel benchmarks and soaks time a step of the paper's fixed 4 projections (comparable
// from one measurement to the next and with the speed targets), not the adaptive default, unless
// --iterations or --tolerance was given.
void usePaperIterationsUnlessGiven(ToolOptions& options);

// Parses argv; keys not in `toolKeys` nor a Parameters field throw InvalidInput naming them.
ToolOptions parseToolOptions(int argc, char** argv, const std::map<std::string, std::string>& toolKeys);

std::string toolUsage(const std::map<std::string, std::string>& toolKeys);

// The whole number given for a tool key, or `fallback` when absent. Throws InvalidInput naming
// the key unless it is a whole number of at least `minimum` (a count of 0 would loop forever).
long toolInteger(const ToolOptions& options, const std::string& key, long fallback, long minimum);

// The positive finite numbers given for a tool key as a comma-separated list (one number is a list
// of one), or {fallback} when absent. Throws InvalidInput naming the key otherwise.
std::vector<double> toolReals(const ToolOptions& options, const std::string& key, double fallback);
inline double toolReal(const ToolOptions& options, const std::string& key, double fallback)
{
  return toolReals(options, key, fallback).front();
}

// The scene --scene names: a preset, or a JSON file (a name with ".json").
Scene toolScene(const ToolOptions& options);

Backend parseBackend(const std::string& name);

} // namespace pbf
