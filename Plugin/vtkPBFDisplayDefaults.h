/**
 * @class   vtkPBFDisplayDefaults
 * @brief   display defaults for Position Based Fluids that proxy XML hints cannot express
 *
 * Applied when a vtkPBFSimulation output is shown, in the GUI, pvpython and pvbatch alike (the
 * plugin installs one instance when it is loaded; it watches the server manager, not Qt):
 * - the Point Gaussian radius is half the ParticleSpacing, so that neighbouring particles touch
 *   and the fluid reads as a volume (the representation's own default is 0.5% of the bounds,
 *   tiny dots), and follows the spacing when it changes unless the user set a radius of their own;
 * - the "velocity" color map grows every time step, because frame 0 is at rest (all speeds 0) and
 *   a range taken then would saturate as soon as the animation plays; it starts again from the
 *   data when the scene (Preset, SceneFile) changes;
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

  struct vtkInternals;
  std::unique_ptr<vtkInternals> Internals;
};

// The free function paraview_add_plugin(INITIALIZERS) calls when the plugin is loaded.
void vtkPBFDisplayDefaultsInstall();

#endif
