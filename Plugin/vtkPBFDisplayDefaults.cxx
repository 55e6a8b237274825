#include "vtkPBFDisplayDefaults.h"

#include "vtkCommand.h"
#include "vtkDataObject.h"
#include "vtkNew.h"
#include "vtkPVArrayInformation.h"
#include "vtkPVDataInformation.h"
#include "vtkObjectFactory.h"
#include "vtkSMPVRepresentationProxy.h"
#include "vtkSMProperty.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMProxy.h"
#include "vtkSMProxyManager.h"
#include "vtkSMSessionProxyManager.h"
#include "vtkSMSourceProxy.h"
#include "vtkSMStringListDomain.h"
#include "vtkSMTransferFunctionManager.h"
#include "vtkSMTransferFunctionProxy.h"
#include "vtkSmartPointer.h"
#include "vtkWeakPointer.h"

#include <algorithm>
#include <cstring>
#include <iterator>
#include <string>
#include <vector>
#include <vector>

namespace
{
// The scene a display last showed (Preset and SceneFile): another scene starts from rest with
// other speeds, so its color map starts again from its data instead of keeping the old range.
std::string SceneOf(vtkSMProxy* producer)
{
  const char* file = vtkSMPropertyHelper(producer, "SceneFile").GetAsString();
  return std::to_string(vtkSMPropertyHelper(producer, "Preset").GetAsInt()) + "|" +
    (file ? file : "");
}

bool IsSimulation(vtkSMProxy* producer)
{
  return producer && producer->GetVTKClassName() &&
    std::strcmp(producer->GetVTKClassName(), "vtkPBFSimulation") == 0;
}

// The particles' data information, valid right after the producer updated (no update is asked).
vtkPVDataInformation* ParticleInformation(vtkSMProxy* producer)
{
  auto* source = vtkSMSourceProxy::SafeDownCast(producer);
  return source && source->GetNumberOfOutputPorts() > 0 ? source->GetDataInformation(0) : nullptr;
}

// The scene's speed scale sqrt(v0^2 + 2 |g| L) that the filter records in the field data
// (SceneSpeed), or 0 where there is none (a failed run).
double SceneSpeedOf(vtkPVDataInformation* info)
{
  vtkPVArrayInformation* array =
    info ? info->GetArrayInformation("SceneSpeed", vtkDataObject::FIELD) : nullptr;
  return array ? array->GetComponentRange(0)[1] : 0.0;
}

// The color map a display colors with, or null.
vtkSMProxy* ColorsOf(vtkSMProxy* display)
{
  return display->GetProperty("LookupTable")
    ? vtkSMPropertyHelper(display, "LookupTable", /*quiet=*/true).GetAsProxy()
    : nullptr;
}

// Whether a color map rescales itself as data changes (the plugin's default, Grow and update
// every timestep, or Grow and update on Apply): a range the user locked or made custom stays.
bool Grows(vtkSMProxy* colors)
{
  const int mode = vtkSMPropertyHelper(colors, "AutomaticRescaleRangeMode").GetAsInt();
  return mode == vtkSMTransferFunctionManager::GROW_ON_APPLY_AND_TIMESTEP ||
    mode == vtkSMTransferFunctionManager::GROW_ON_APPLY;
}

// The columns of the Diagnostics table, in the filter's order; only the density errors are
// plotted at first (the others are on other scales, one click away in the series list).
const char* const DiagnosticsColumns[] = { "AverageDensityError", "MaxDensityError",
  "AverageNeighbors", "SolverIterations", "MillisecondsPerStep", "Substeps", "MinTimeStep",
  "MaxTimeStep", "MaxSpeed", "KineticEnergy", "Frame", "Particles" };
} // namespace

struct vtkPBFDisplayDefaults::vtkInternals
{
  // A particle display and what this class last gave it: a display whose radius still equals
  // FollowedRadius was not changed by the user, so it follows the spacing.
  struct Followed
  {
    vtkWeakPointer<vtkSMProxy> Display;
    vtkWeakPointer<vtkSMProxy> Producer;
    double FollowedRadius = 0;
    std::string Scene;
    // The producer's SceneSpeed at its latest update: the velocity color map's least top.
    double SceneSpeed = 0;
  };
  std::vector<Followed> Displays;
  // Everything observed, with the observer's tag, so that the destructor can detach from what
  // still exists.
  template <class T>
  struct Watched
  {
    vtkWeakPointer<T> Object;
    unsigned long Tag;
  };
  std::vector<Watched<vtkSMSessionProxyManager>> Sessions;
  std::vector<Watched<vtkSMProxy>> Producers;
  std::vector<Watched<vtkSMProxy>> ColorMaps;
  // Set while this class rescales a color map, whose own change notices must not recurse.
  bool Widening = false;
  Watched<vtkSMProxyManager> Manager{ nullptr, 0 };

  template <class T>
  static void Detach(std::vector<Watched<T>>& watched)
  {
    for (auto& w : watched)
    {
      if (w.Object)
      {
        w.Object->RemoveObserver(w.Tag);
      }
    }
    watched.clear();
  }

  template <class T>
  static bool Has(std::vector<Watched<T>>& watched, T* object)
  {
    watched.erase(std::remove_if(watched.begin(), watched.end(),
                    [](const Watched<T>& w) { return !w.Object; }),
      watched.end());
    return std::any_of(
      watched.begin(), watched.end(), [object](const Watched<T>& w) { return w.Object == object; });
  }

  void Prune()
  {
    Displays.erase(std::remove_if(Displays.begin(), Displays.end(),
                     [](const Followed& f) { return !f.Display || !f.Producer; }),
      Displays.end());
  }
};

vtkStandardNewMacro(vtkPBFDisplayDefaults);

//------------------------------------------------------------------------------
vtkPBFDisplayDefaults::vtkPBFDisplayDefaults()
  : Internals(new vtkInternals)
{
}

//------------------------------------------------------------------------------
vtkPBFDisplayDefaults::~vtkPBFDisplayDefaults()
{
  // Whatever still exists must not call back into a deleted object.
  vtkInternals::Detach(this->Internals->Sessions);
  vtkInternals::Detach(this->Internals->Producers);
  vtkInternals::Detach(this->Internals->ColorMaps);
  if (this->Internals->Manager.Object)
  {
    this->Internals->Manager.Object->RemoveObserver(this->Internals->Manager.Tag);
  }
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::Install()
{
  // One per process, for the process's life: the plugin is loaded once and never unloaded.
  static vtkSmartPointer<vtkPBFDisplayDefaults> instance;
  if (instance || !vtkSMProxyManager::IsInitialized())
  {
    return; // loaded again, or in a process without a server manager (nothing is shown there)
  }
  instance = vtkSmartPointer<vtkPBFDisplayDefaults>::New();
  vtkSMProxyManager* manager = vtkSMProxyManager::GetProxyManager();
  instance->Internals->Manager = { manager,
    manager->AddObserver(vtkSMProxyManager::ActiveSessionChanged, instance.Get(),
      &vtkPBFDisplayDefaults::OnActiveSessionChanged) };
  instance->OnActiveSessionChanged(manager, vtkSMProxyManager::ActiveSessionChanged, nullptr);
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::OnActiveSessionChanged(vtkObject*, unsigned long, void*)
{
  vtkSMProxyManager* manager = this->Internals->Manager.Object;
  vtkSMSessionProxyManager* session = manager ? manager->GetActiveSessionProxyManager() : nullptr;
  if (!session || vtkInternals::Has(this->Internals->Sessions, session))
  {
    return;
  }
  this->Internals->Sessions.push_back({ session,
    session->AddObserver(vtkCommand::RegisterEvent, this, &vtkPBFDisplayDefaults::OnRegistered) });
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::OnRegistered(vtkObject* caller, unsigned long, void* callData)
{
  auto* info = static_cast<vtkSMProxyManager::RegisteredProxyInformation*>(callData);
  if (info && info->Type == vtkSMProxyManager::RegisteredProxyInformation::PROXY && info->Proxy &&
    info->GroupName && std::strcmp(info->GroupName, "representations") == 0)
  {
    this->Adopt(info->Proxy, vtkSMSessionProxyManager::SafeDownCast(caller));
  }
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::Adopt(vtkSMProxy* display, vtkSMSessionProxyManager* proxyManager)
{
  if (!display || !display->GetProperty("Input"))
  {
    return;
  }
  vtkSMPropertyHelper input(display, "Input", /*quiet=*/true);
  vtkSMProxy* producer = input.GetAsProxy();
  if (!IsSimulation(producer))
  {
    return;
  }
  // A state file gives its displays their properties: they are followed, not reset.
  const bool fromState = proxyManager && proxyManager->GetInLoadXMLState();

  if (input.GetOutputPort() == 1 && display->GetProperty("SeriesVisibility"))
  {
    if (!fromState)
    {
      // Every series the chart offers (the loads' columns too, named after the scene's
      // obstacles and the tank's walls, with their components), else the filter's own columns.
      std::vector<std::string> series;
      auto* offered = vtkSMStringListDomain::SafeDownCast(
        display->GetProperty("SeriesVisibility")->FindDomain("vtkSMChartSeriesSelectionDomain"));
      for (unsigned int k = 0; offered && k < offered->GetNumberOfStrings(); ++k)
      {
        series.emplace_back(offered->GetString(k));
      }
      if (series.empty())
      {
        series.assign(std::begin(DiagnosticsColumns), std::end(DiagnosticsColumns));
      }
      vtkSMPropertyHelper visibility(display, "SeriesVisibility");
      unsigned int element = 0;
      for (const std::string& column : series)
      {
        const bool shown = column == "AverageDensityError" || column == "MaxDensityError";
        visibility.Set(element++, column.c_str());
        visibility.Set(element++, shown ? "1" : "0");
      }
      display->UpdateVTKObjects();
    }
    return;
  }
  // The particles (port 0) in a view that draws Point Gaussians; the Domain outline (port 2)
  // keeps the representation's defaults.
  if (input.GetOutputPort() != 0 || !display->GetProperty("GaussianRadius"))
  {
    return;
  }
  const double spacing = vtkSMPropertyHelper(producer, "ParticleSpacing").GetAsDouble();
  if (!fromState)
  {
    vtkSMPropertyHelper(display, "GaussianRadius").Set(0.5 * spacing);
    display->UpdateVTKObjects();
    // The color map is the session's one for arrays named "velocity", the one Show picks.
    vtkNew<vtkSMTransferFunctionManager> colorMaps;
    if (vtkSMProxy* colors = colorMaps->GetColorTransferFunction(
          "velocity", proxyManager ? proxyManager : display->GetSessionProxyManager()))
    {
      vtkSMPropertyHelper(colors, "AutomaticRescaleRangeMode")
        .Set(vtkSMTransferFunctionManager::GROW_ON_APPLY_AND_TIMESTEP);
      colors->UpdateVTKObjects();
      // Whoever sets its range (Show's first coloring, Apply, the animation) is followed by the
      // floor [0, SceneSpeed]: frame 0 is at rest, and a range taken there reads 0 to 1e-38.
      if (!vtkInternals::Has(this->Internals->ColorMaps, colors))
      {
        this->Internals->ColorMaps.push_back({ colors,
          colors->AddObserver(
            vtkCommand::PropertyModifiedEvent, this, &vtkPBFDisplayDefaults::OnColorsModified) });
      }
    }
  }
  vtkInternals::Followed followed;
  followed.Display = display;
  followed.Producer = producer;
  followed.FollowedRadius = 0.5 * spacing;
  followed.Scene = SceneOf(producer);
  this->Internals->Prune();
  this->Internals->Displays.push_back(followed);
  if (!vtkInternals::Has(this->Internals->Producers, producer))
  {
    this->Internals->Producers.push_back({ producer,
      producer->AddObserver(
        vtkCommand::UpdateDataEvent, this, &vtkPBFDisplayDefaults::OnDataUpdated) });
  }
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::OnDataUpdated(vtkObject* caller, unsigned long, void*)
{
  vtkSMProxy* producer = vtkSMProxy::SafeDownCast(caller);
  this->Internals->Prune();
  for (vtkInternals::Followed& followed : this->Internals->Displays)
  {
    if (followed.Producer != producer)
    {
      continue;
    }
    vtkSMProxy* display = followed.Display;
    // The spacing changed (the data is then computed again): the spheres touch again, unless the
    // user has set a radius of their own.
    const double radius = vtkSMPropertyHelper(display, "GaussianRadius").GetAsDouble();
    const double wanted = 0.5 * vtkSMPropertyHelper(producer, "ParticleSpacing").GetAsDouble();
    if (radius == followed.FollowedRadius && radius != wanted)
    {
      vtkSMPropertyHelper(display, "GaussianRadius").Set(wanted);
      display->UpdateVTKObjects();
      followed.FollowedRadius = wanted;
    }
    vtkPVDataInformation* info = ParticleInformation(producer);
    followed.SceneSpeed = SceneSpeedOf(info);
    const std::string scene = SceneOf(producer);
    if (scene != followed.Scene)
    {
      followed.Scene = scene;
      vtkSMPVRepresentationProxy::RescaleTransferFunctionToDataRange(
        display, /*extend=*/false, /*force=*/true);
    }
    // A new time shown through the view (ViewTime) or asked of the source (UpdatePipeline(t))
    // grows the map as an animation tick does: ParaView grows it on ticks alone.
    vtkSMProxy* colors = ColorsOf(display);
    vtkPVArrayInformation* velocity =
      info ? info->GetArrayInformation("velocity", vtkDataObject::POINT) : nullptr;
    const char* colored = vtkSMPropertyHelper(display, "ColorArrayName").GetInputArrayNameToProcess();
    if (colors && velocity && colored && std::strcmp(colored, "velocity") == 0 && Grows(colors))
    {
      vtkSMTransferFunctionProxy::RescaleTransferFunction(
        colors, velocity->GetComponentRange(-1), /*extend=*/true);
      colors->UpdateVTKObjects();
    }
    this->WidenToSceneSpeed(colors);
  }
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::OnColorsModified(vtkObject* caller, unsigned long, void* callData)
{
  const char* name = static_cast<const char*>(callData);
  if (!this->Internals->Widening && name && std::strcmp(name, "RGBPoints") == 0)
  {
    this->WidenToSceneSpeed(vtkSMProxy::SafeDownCast(caller));
  }
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::WidenToSceneSpeed(vtkSMProxy* colors)
{
  if (!colors || this->Internals->Widening || !Grows(colors))
  {
    return;
  }
  // The floor is the fastest scene among the displays this map colors.
  this->Internals->Prune();
  double top = 0;
  for (const vtkInternals::Followed& followed : this->Internals->Displays)
  {
    vtkSMProxy* display = followed.Display;
    if (ColorsOf(display) == colors)
    {
      top = std::max(top, followed.SceneSpeed);
    }
  }
  double range[2];
  if (top <= 0 || !vtkSMTransferFunctionProxy::GetRange(colors, range) ||
    (range[0] <= 0 && range[1] >= top))
  {
    return;
  }
  this->Internals->Widening = true;
  vtkSMTransferFunctionProxy::RescaleTransferFunction(
    colors, std::min(range[0], 0.0), std::max(range[1], top));
  colors->UpdateVTKObjects();
  this->Internals->Widening = false;
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Displays: " << this->Internals->Displays.size() << "\n";
  os << indent << "Sessions: " << this->Internals->Sessions.size() << "\n";
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaultsInstall()
{
  vtkPBFDisplayDefaults::Install();
}
