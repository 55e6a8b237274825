/**
 * @class   vtkPBFDisplayDefaults
 * @brief   display defaults for Position Based Fluids that proxy XML hints cannot express
 *
 * Applied when a vtkPBFSimulation output is shown, in the GUI, pvpython and pvbatch alike (the
 * plugin installs one instance when it is loaded; it watches the server manager, not Qt):
 * - the Point Gaussian radius is half the ParticleSpacing, so that neighbouring particles touch
 *   and the fluid reads as a volume (the representation's own default is 0.5% of the bounds,
 *   tiny dots), and follows the spacing when it changes unless the user set a radius of their own;
 * - the "velocity" color map starts at [0, SceneSpeed] (the scene's speed scale sqrt(2 g H) from
 *   the field data), because frame 0 is at rest and a range taken there reads 0 to 1e-38, and
 *   grows with every time shown (the animation, a view's ViewTime, a source's UpdatePipeline(t));
 *   it starts again from [0, SceneSpeed] when the scene (Preset, SceneFile) changes. A range the
 *   user locks or sets (another AutomaticRescaleRangeMode) is left alone;
 * - the Diagnostics table (output port 1) in a Line Chart View plots the two density errors (in
 *   percent) against Time, instead of every column on one axis.
 * Displays loaded from a state file keep the properties the state gives them.
 */
#ifndef vtkPBFDisplayDefaults_h
#define vtkPBFDisplayDefaults_h

#include "vtkObject.h"

#include <memory>

class vtkSMProxy;
class vtkSMSessionProxyManager;

class vtkPBFDisplayDefaults : public vtkObject
{
public:
  static vtkPBFDisplayDefaults* New();
  vtkTypeMacro(vtkPBFDisplayDefaults, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /**
   * The plugin's initializer: creates the process's one instance, which watches every session
   * that becomes active from now on.
   */
  static void Install();

  /**
   * Applies the defaults to `display` when it shows an output of a vtkPBFSimulation; any other
   * representation is left alone.
   */
  void Adopt(vtkSMProxy* display, vtkSMSessionProxyManager* proxyManager);

protected:
  vtkPBFDisplayDefaults();
  ~vtkPBFDisplayDefaults() override;

private:
  vtkPBFDisplayDefaults(const vtkPBFDisplayDefaults&) = delete;
  void operator=(const vtkPBFDisplayDefaults&) = delete;

  void OnActiveSessionChanged(vtkObject* caller, unsigned long event, void* callData);
  void OnRegistered(vtkObject* caller, unsigned long event, void* callData);
  void OnDataUpdated(vtkObject* producer, unsigned long event, void* callData);
  void OnColorsModified(vtkObject* colors, unsigned long event, void* callData);
  // Extends a growing color map to [0, SceneSpeed] of the scenes it colors.
  void WidenToSceneSpeed(vtkSMProxy* colors);

  struct vtkInternals;
  std::unique_ptr<vtkInternals> Internals;
};

// The free function paraview_add_plugin(INITIALIZERS) calls when the plugin is loaded.
void vtkPBFDisplayDefaultsInstall();

#endif
