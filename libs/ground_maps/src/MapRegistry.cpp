#include <gam/maps/GridIO.h>
#include <gam/maps/IniFields.h>
#include <gam/maps/MapRegistry.h>
#include <mrpt/maps/COccupancyGridMap2D.h>

#include <map>
#include <mutex>

namespace gam::maps
{
namespace
{
struct Registry
{
	std::mutex mutex;
	std::map<std::string, MapTraits> byName;
};
Registry& registry()
{
	static Registry r;  // constructed on first use: safe from other libraries' initializers
	return r;
}

// Every COccupancyGridMap2D (the stock one and any subclass without traits of
// its own) gets the grid outputs and the local window.
const bool kGridTraits = [] {
	MapTraits t;
	t.className = "mrpt::maps::COccupancyGridMap2D";
	t.writeOutputs = writeGridOutputs;
	t.keepWindow = keepGridWindow;
	t.startFromGrid = startGridFromStock;
	registerMapTraits(std::move(t));
	return true;
}();
}  // namespace

void registerMapTraits(MapTraits t)
{
	Registry& r = registry();
	std::lock_guard<std::mutex> lock(r.mutex);
	const std::string name = t.className;
	r.byName[name] = std::move(t);
}

const MapTraits* findMapTraits(const std::string& className)
{
	Registry& r = registry();
	std::lock_guard<std::mutex> lock(r.mutex);
	const auto it = r.byName.find(className);
	return it == r.byName.end() ? nullptr : &it->second;
}

const MapTraits* findMapTraits(const mrpt::rtti::TRuntimeClassId* cls)
{
	for (; cls; cls = cls->getBaseClass ? cls->getBaseClass() : nullptr)
		if (const MapTraits* t = findMapTraits(std::string(cls->className))) return t;
	return nullptr;
}

const MapTraits* findMapTraits(const mrpt::maps::CMetricMap& map) { return findMapTraits(map.GetRuntimeClass()); }

std::vector<std::string> gridCreationKeys()
{
	std::vector<std::string> k = ini::keys<ini::GridExtent>();
	for (const char* g : {"label", "enableSaveAs3DObject", "enableObservationLikelihood", "enableObservationInsertion"})
		k.push_back(g);
	return k;
}

void startGridFromStock(mrpt::maps::CMetricMap& map, const mrpt::maps::COccupancyGridMap2D& stock)
{
	copyGridCells(stock, dynamic_cast<mrpt::maps::COccupancyGridMap2D&>(map));
}

void keepGridWindow(mrpt::maps::CMetricMap& map, double x, double y, int cells)
{
	recentreGrid(dynamic_cast<mrpt::maps::COccupancyGridMap2D&>(map), x, y, cells);
}

void writeGridOutputs(mrpt::maps::CMetricMap& map, const OutputContext& ctx, std::vector<std::string>& files)
{
	auto& g = dynamic_cast<mrpt::maps::COccupancyGridMap2D&>(map);
	// A grid that was not recentred after every frame (the octomap's
	// projection) is cropped to the last window here; a no-op for the others.
	if (ctx.localMap) recentreGrid(g, ctx.robotX, ctx.robotY, ctx.localCells);
	const std::string base = ctx.dir + "/" + ctx.label;
	writeRosMap(g, base + ".yaml", base + ".pgm", ctx.label + ".pgm");
	writePlainGridmapGz(g, base + ".gridmap.gz");
	PngStyle style;
	style.legend = ctx.pngLegend;
	writeGridPng(g, base + ".png", style);
	for (const char* ext : {".yaml", ".pgm", ".gridmap.gz", ".png"}) files.push_back(ctx.label + ext);
}

}  // namespace gam::maps
