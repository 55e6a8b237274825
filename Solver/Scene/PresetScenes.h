// The JSON text of the scenes in Data/, generated at build time from the files themselves.
#pragma once

#include <cstddef>

namespace pbf
{

struct PresetText
{
  const char* name;
  const char* json;
};

extern const PresetText kPresetScenes[];
extern const std::size_t kPresetSceneCount;

} // namespace pbf
