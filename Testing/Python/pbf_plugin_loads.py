"""The plugin loads and defines a source and a filter whose properties are documented, bounded and
grouped, whose presets are the scenes in Data/, and whose output is shown as particles."""
import glob
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pbf_testing as T  # noqa: E402
from paraview import servermanager  # noqa: E402
from paraview.simple import PointSource  # noqa: E402

T.load_plugin(globals())

GROUPS = ["Scene", "Fluid", "Solver", "Time", "Surface", "Backend"]
BOUNDING_DOMAINS = {"vtkSMIntRangeDomain", "vtkSMDoubleRangeDomain", "vtkSMEnumerationDomain",
                    "vtkSMFileListDomain", "vtkSMBooleanDomain"}

source = PositionBasedFluids()  # noqa: F821 (defined by LoadPlugin)
seed = PointSource(Center=[0.8, 0.4, 0.3], Radius=0.1, NumberOfPoints=10)
fluid_filter = PositionBasedFluidsFromPoints(Input=seed)  # noqa: F821

pxm = servermanager.ProxyManager()
expect = T.expect
expect(pxm.SMProxyManager.GetPrototypeProxy("sources", "PBFSimulationSource") is not None,
       "the source is not in the sources group (Sources menu)")
expect(pxm.SMProxyManager.GetPrototypeProxy("filters", "PBFSimulationFilter") is not None,
       "the filter is not in the filters group (Filters menu)")


def check_proxy(proxy, label):
    sm = proxy.SMProxy
    expect(sm.GetVTKClassName() == "vtkPBFSimulation",
           "%s drives %s, not vtkPBFSimulation" % (label, sm.GetVTKClassName()))

    # Property groups: the five of the brief, in order, each property in exactly one.
    groups = [sm.GetPropertyGroup(i) for i in range(sm.GetNumberOfPropertyGroups())]
    labels = [g.GetXMLLabel() for g in groups]
    expect(labels == GROUPS, "%s: property groups %s, expected %s" % (label, labels, GROUPS))
    grouped = {}
    for group in groups:
        for i in range(group.GetNumberOfProperties()):
            name = sm.GetPropertyName(group.GetProperty(i))
            expect(name not in grouped, "%s: %s is in two groups" % (label, name))
            grouped[name] = group.GetXMLLabel()

    iterator = sm.NewPropertyIterator()
    iterator.Begin()
    settable = []
    while not iterator.IsAtEnd():
        name, prop = iterator.GetKey(), iterator.GetProperty()
        iterator.Next()
        documentation = prop.GetDocumentation()
        text = documentation.GetDescription() if documentation else ""
        expect(text and len(text.split()) >= 5,
               "%s.%s has no documentation worth the name: %r" % (label, name, text))
        if prop.GetInformationOnly():
            continue
        if name == "Input":
            continue
        settable.append(name)
        expect(name in grouped, "%s.%s is in no property group" % (label, name))
        if prop.IsA("vtkSMInputProperty"):
            continue  # bounded by its data type domain, checked below
        domains = []
        domain_iterator = prop.NewDomainIterator()
        domain_iterator.Begin()
        while not domain_iterator.IsAtEnd():
            domains.append(domain_iterator.GetDomain())
            domain_iterator.Next()
        bounding = [d for d in domains if d.GetClassName() in BOUNDING_DOMAINS]
        expect(bounding, "%s.%s has no bounding domain (has %s)"
               % (label, name, [d.GetClassName() for d in domains]))
        for domain in bounding:
            if domain.GetClassName() in ("vtkSMIntRangeDomain", "vtkSMDoubleRangeDomain"):
                for element in range(prop.GetNumberOfElements()):
                    expect(domain.GetMinimumExists(element) and domain.GetMaximumExists(element),
                           "%s.%s[%d]: the range needs a minimum and a maximum"
                           % (label, name, element))
    expect(len(settable) == len(grouped),
           "%s: grouped %s but settable %s" % (label, sorted(grouped), sorted(settable)))

    timesteps = sm.GetProperty("TimestepValues")
    expect(timesteps is not None and timesteps.GetInformationOnly(),
           "%s: TimestepValues must be an information-only property" % label)

    hints = sm.GetHints()
    expect(hints is not None, "%s has no hints" % label)
    representation = hints.FindNestedElementByName("RepresentationType")
    expect(representation is not None and
           representation.GetAttribute("type") in ("Point Gaussian", "Points"),
           "%s: no RepresentationType hint that shows particles" % label)

    # Five output ports: the particles; the diagnostics table, which Apply shows in no view
    # (a chart opened on Apply would split the layout and draw a single row), a Line Chart
    # View plots it when its eye is clicked (pbf_diagnostics.py checks what Apply does); the
    # domain's outline, shown with the particles so that the camera frames the tank; the
    # surface, which Apply does not show either (the particles stay the default display); the
    # probes' table, not shown either (Plot Data Over Time draws it).
    ports = [sm.GetOutputPortName(i) for i in range(sm.GetNumberOfOutputPorts())]
    expect(ports == ["Particles", "Diagnostics", "Domain", "Surface", "Probes"],
           "%s: output ports %s" % (label, ports))
    views = [hints.GetNestedElement(i) for i in range(hints.GetNumberOfNestedElements())
             if hints.GetNestedElement(i).GetName() == "View"]
    expect([(v.GetAttribute("type"), v.GetAttribute("port")) for v in views] ==
           [("None", "1"), ("None", "3"), ("None", "4")],
           "%s: the diagnostics', surface's and probes' View hints are %s, not None"
           % (label, [(v.GetAttribute("type"), v.GetAttribute("port")) for v in views]))

    # SceneFile: the GUI's file dialog, filtered to JSON scenes.
    scene_file = sm.GetProperty("SceneFile")
    expect(scene_file.FindDomain("vtkSMFileListDomain") is not None,
           "%s.SceneFile has no file list domain (no file dialog)" % label)
    chooser = scene_file.GetHints().FindNestedElementByName("FileChooser")
    expect(chooser is not None and chooser.GetAttribute("extensions") == "json",
           "%s.SceneFile: the file dialog is not filtered to .json" % label)


check_proxy(source, "source")
check_proxy(fluid_filter, "filter")

expect(source.SMProxy.GetProperty("Input") is None, "the source must not take an input")
input_property = fluid_filter.SMProxy.GetProperty("Input")
expect(input_property is not None, "the filter has no Input property")
definition = pxm.SMProxyManager.GetProxyDefinitionManager().GetCollapsedProxyDefinition(
    "filters", "PBFSimulationFilter", None, False)
input_xml = [definition.GetNestedElement(i) for i in range(definition.GetNumberOfNestedElements())
             if definition.GetNestedElement(i).GetName() == "InputProperty" and
             definition.GetNestedElement(i).GetAttribute("name") == "Input"][0]
data_type_xml = input_xml.FindNestedElementByName("DataTypeDomain")
accepted = [data_type_xml.GetNestedElement(i).GetAttribute("value")
            for i in range(data_type_xml.GetNumberOfNestedElements())
            if data_type_xml.GetNestedElement(i).GetName() == "DataType"]
expect(accepted == ["vtkPointSet"], "the filter's input accepts %s, not any vtkPointSet" % accepted)

# Both proxies take obstacles on port 1: as many as the user gives, none required.
for proxy, label in ((source, "source"), (fluid_filter, "filter")):
    obstacles = proxy.SMProxy.GetProperty("Obstacles")
    expect(obstacles is not None and obstacles.IsA("vtkSMInputProperty"),
           "%s has no Obstacles input property" % label)
    expect(obstacles.GetPortIndex() == 1, "%s.Obstacles is on port %d, not 1"
           % (label, obstacles.GetPortIndex()))
    expect(obstacles.GetMultipleInput() == 1, "%s.Obstacles takes one input only" % label)
    expect(obstacles.GetHints() is not None and
           obstacles.GetHints().FindNestedElementByName("Optional") is not None,
           "%s.Obstacles is not marked optional" % label)
    # Which datasets it takes is shown by pbf_obstacles.py (poly data from sources and readers).
    expect(obstacles.GetDomain("input_type") is not None,
           "%s.Obstacles has no data type domain" % label)

# The preset enumeration names the scenes compiled in from Data/ (file names without .json).
enumeration = source.SMProxy.GetProperty("Preset").GetDomain("enum")
presets = [enumeration.GetEntryText(i) for i in range(enumeration.GetNumberOfEntries())]
expect(presets == ["dam_break", "double_dam_break", "blob", "stream", "marin_dam_break",
                  "channel"],
       "preset entries %s" % presets)
expect(source.Preset == "dam_break", "the default preset is %s, not dam_break" % source.Preset)
data_dir = os.environ.get("PBF_DATA_DIR")
if data_dir:
    shipped = sorted(os.path.splitext(os.path.basename(f))[0]
                     for f in glob.glob(os.path.join(data_dir, "*.json")))
    expect(sorted(presets) == shipped,
           "presets %s but Data/ ships %s" % (sorted(presets), shipped))

backends = source.SMProxy.GetProperty("Backend").GetDomain("enum")
expect([backends.GetEntryText(i) for i in range(backends.GetNumberOfEntries())] ==
       ["Auto", "CUDA", "CPU (OpenMP)", "Serial"], "backend entries")
expect(source.Backend == "Auto" and source.Precision == "Single",
       "default backend/precision: %s/%s" % (source.Backend, source.Precision))

T.passed("PluginLoads")
