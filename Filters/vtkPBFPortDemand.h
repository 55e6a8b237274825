// Which outputs of vtkPBFSimulation one execution makes. The executive asks an algorithm for
// every output port at once, but says which port's consumer asked (FROM_OUTPUT_PORT), and lets
// the algorithm mark the outputs it leaves as they were (DATA_NOT_GENERATED): a port so left is
// executed again when someone asks for it. The surface (port 3) is the costly one that few views
// show, so it is made only when a consumer of its own asks, or GenerateSurface keeps it made.
// Internal to PBF::Filters.
#ifndef vtkPBFPortDemand_h
#define vtkPBFPortDemand_h

class vtkAlgorithm;
class vtkInformation;
class vtkInformationVector;

struct vtkPBFPortDemand
{
  // The particles, diagnostics, domain and probes (ports 0, 1, 2, 4) of the requested frame.
  bool Frame = true;
  // The surface of the particles on port 0 (port 3).
  bool Surface = false;
  // A request through the surface's port that leaves it unmade (nobody below the port looks at
  // it): what the port's consumers then hold is not the frame's surface, so the next request
  // through that port must reach the algorithm again (vtkPBFSimulation::ComputePipelineMTime).
  bool LeftStale = false;

  // What the request needs. surfacePort: the surface's port; keepSurface: GenerateSurface;
  // frameHeld: the internals hold the requested frame (its time frameTime) as port 0's data.
  // Called for REQUEST_DATA_NOT_GENERATED, before the REQUEST_DATA it describes.
  static vtkPBFPortDemand Of(vtkAlgorithm* algorithm, vtkInformation* request,
    vtkInformationVector* outputVector, int surfacePort, bool keepSurface, bool frameHeld,
    double frameTime);

  // Marks the outputs this demand leaves as they are (DATA_NOT_GENERATED).
  void MarkNotGenerated(vtkInformationVector* outputVector, int surfacePort) const;
};

#endif
