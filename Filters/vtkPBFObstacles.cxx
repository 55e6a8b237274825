#include "vtkPBFObstacles.h"

#include "vtkCellArray.h"
#include "vtkCleanPolyData.h"
#include "vtkDataSet.h"
#include "vtkFieldData.h"
#include "vtkStringArray.h"
#include "vtkDataSetSurfaceFilter.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkOBJReader.h"
#include "vtkPLYReader.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkAlgorithm.h"
#include "vtkSTLReader.h"
#include "vtkSmartPointer.h"
#include "vtkTriangleFilter.h"
#include "vtkXMLPolyDataReader.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

//------------------------------------------------------------------------------
pbf::SolidRegion vtkPBFSolidFromInput(vtkDataSet* input, double thickness, const std::string& name)
{
  if (!input || input->GetNumberOfPoints() == 0 || input->GetNumberOfCells() == 0)
  {
    throw pbf::InvalidInput(name + ": the dataset is empty (no points or no cells)");
  }
  vtkSmartPointer<vtkPolyData> surface = vtkPolyData::SafeDownCast(input);
  if (!surface)
  {
    vtkNew<vtkDataSetSurfaceFilter> outer;
    outer->SetInputData(input);
    outer->Update();
    surface = outer->GetOutput();
  }
  // Points merged only where they coincide exactly (a Box source's faces repeat its corners):
  // a tolerance would move the surface.
  vtkNew<vtkCleanPolyData> merged;
  merged->SetInputData(surface);
  merged->SetTolerance(0.0);
  merged->PointMergingOn();
  merged->ConvertLinesToPointsOff();
  merged->ConvertPolysToLinesOff();
  merged->ConvertStripsToPolysOff();
  vtkNew<vtkTriangleFilter> triangles;
  triangles->SetInputConnection(merged->GetOutputPort());
  triangles->PassLinesOff();
  triangles->PassVertsOff();
  triangles->Update();
  vtkPolyData* mesh = triangles->GetOutput();

  pbf::SolidRegion solid;
  solid.kind = pbf::SolidRegion::Kind::Mesh;
  solid.thickness = thickness;
  solid.name = name;
  vtkPoints* points = mesh->GetPoints();
  const vtkIdType n = points ? points->GetNumberOfPoints() : 0;
  solid.mesh.points.resize(static_cast<std::size_t>(n));
  for (vtkIdType i = 0; i < n; ++i)
  {
    double p[3];
    points->GetPoint(i, p);
    solid.mesh.points[static_cast<std::size_t>(i)] = pbf::Vec3d{ p[0], p[1], p[2] };
  }
  vtkCellArray* polys = mesh->GetPolys();
  vtkNew<vtkIdList> ids;
  for (polys->InitTraversal(); polys->GetNextCell(ids);)
  {
    if (ids->GetNumberOfIds() == 3)
    {
      solid.mesh.triangles.push_back({ static_cast<std::uint32_t>(ids->GetId(0)),
        static_cast<std::uint32_t>(ids->GetId(1)), static_cast<std::uint32_t>(ids->GetId(2)) });
    }
  }
  if (solid.mesh.triangles.empty())
  {
    throw pbf::InvalidInput(name + ": its surface has no polygons (" +
      std::to_string(input->GetNumberOfCells()) +
      " cells, none of them a face of a solid): an obstacle needs a surface that bounds a solid");
  }
  return solid;
}

//------------------------------------------------------------------------------
void vtkPBFReadMeshFiles(pbf::Scene& scene)
{
  for (std::size_t k = 0; k < scene.solids.size(); ++k)
  {
    pbf::SolidRegion& solid = scene.solids[k];
    if (solid.kind != pbf::SolidRegion::Kind::Mesh || solid.file.empty())
    {
      continue;
    }
    const std::string field = "obstacles[" + std::to_string(k) + "].file = \"" + solid.file + "\"";
    std::error_code error;
    if (!std::filesystem::is_regular_file(solid.file, error))
    {
      throw pbf::InvalidInput(field + ": no such file");
    }
    std::string extension = std::filesystem::path(solid.file).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
      [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    // VTK's reader for the extension; each takes SetFileName.
    auto open = [&](auto made) {
      made->SetFileName(solid.file.c_str());
      return vtkSmartPointer<vtkAlgorithm>(made);
    };
    const vtkSmartPointer<vtkAlgorithm> reader = extension == ".stl"
      ? open(vtkSmartPointer<vtkSTLReader>::New())
      : extension == ".obj" ? open(vtkSmartPointer<vtkOBJReader>::New())
      : extension == ".ply" ? open(vtkSmartPointer<vtkPLYReader>::New())
      : extension == ".vtp" ? open(vtkSmartPointer<vtkXMLPolyDataReader>::New())
                            : nullptr;
    if (!reader)
    {
      throw pbf::InvalidInput(field + ": not an STL, OBJ, PLY or VTP file (by its extension)");
    }
    reader->Update();
    const pbf::SolidRegion read = vtkPBFSolidFromInput(
      vtkPolyData::SafeDownCast(reader->GetOutputDataObject(0)), solid.thickness, field);
    solid.mesh = read.mesh;
    solid.name = field;
  }
}

//------------------------------------------------------------------------------
std::vector<std::string> vtkPBFSceneMeshFiles(const std::string& sceneFile)
{
  std::vector<std::string> files;
  if (sceneFile.empty())
  {
    return files;
  }
  try
  {
    for (const pbf::SolidRegion& solid : pbf::loadSceneFile(sceneFile).solids)
    {
      if (!solid.file.empty())
      {
        files.push_back(solid.file);
      }
    }
  }
  catch (const std::exception&)
  {
  }
  return files;
}

//------------------------------------------------------------------------------
std::string vtkPBFFileVersions(const std::vector<std::string>& files)
{
  std::string versions;
  for (const std::string& file : files)
  {
    std::error_code error;
    const auto size = std::filesystem::file_size(file, error);
    const auto time = std::filesystem::last_write_time(file, error);
    versions += "\nmesh " + file + " " + std::to_string(error ? 0 : size) + " " +
      std::to_string(error ? 0 : time.time_since_epoch().count());
  }
  return versions;
}

//------------------------------------------------------------------------------
vtkPBFBodyTag vtkPBFBodyTagOf(vtkDataSet* obstacle)
{
  vtkPBFBodyTag tag;
  vtkFieldData* fields = obstacle ? obstacle->GetFieldData() : nullptr;
  vtkDataArray* density = fields ? fields->GetArray("PBFBodyDensity") : nullptr;
  if (density && density->GetNumberOfTuples() > 0)
  {
    tag.Tagged = true;
    tag.Density = density->GetComponent(0, 0);
    auto* name = vtkStringArray::SafeDownCast(fields->GetAbstractArray("PBFBodyName"));
    if (name && name->GetNumberOfValues() > 0)
    {
      tag.Name = name->GetValue(0);
    }
    // Absent (a dataset marked by an older filter): every freedom, no hold.
    vtkDataArray* axes = fields->GetArray("PBFBodyFreeAxes");
    if (axes && axes->GetNumberOfTuples() > 0 && axes->GetNumberOfComponents() == 3)
    {
      for (int a = 0; a < 3; ++a)
      {
        tag.FreeAxes[a] = axes->GetComponent(0, a) != 0;
      }
    }
    vtkDataArray* turns = fields->GetArray("PBFBodyTurns");
    if (turns && turns->GetNumberOfTuples() > 0)
    {
      tag.Turns = turns->GetComponent(0, 0) != 0;
    }
    vtkDataArray* release = fields->GetArray("PBFBodyRelease");
    if (release && release->GetNumberOfTuples() > 0)
    {
      tag.Release = release->GetComponent(0, 0);
    }
  }
  return tag;
}
