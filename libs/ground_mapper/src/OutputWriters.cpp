// ground-aware-mapper's outputs: each map writes what its traits say
// (gam/maps/MapRegistry.h); a map with no traits (a stock MRPT map) writes
// MRPT's own representation and the serialized object.
#include <gam/mapper/Mapper.h>
#include <gam/maps/GridIO.h>
#include <gam/maps/MapRegistry.h>

#include <filesystem>
#include <set>

namespace fs = std::filesystem;

namespace gam::mapper
{
void Mapper::writeMaps(const std::string& dir, std::vector<std::string>& files)
{
	for (size_t i = 0; i < m_specs.size(); i++)
	{
		auto& map = *m_maps.maps[i];
		const std::string L = m_specs[i].label;
		const std::string base = dir + "/" + L;
		if (const gam::maps::MapTraits* t = gam::maps::findMapTraits(map); t && t->writeOutputs)
		{
			gam::maps::OutputContext ctx;
			ctx.dir = dir;
			ctx.label = L;
			ctx.localMap = m_opts.localMap;
			ctx.robotX = m_lastPose.x();
			ctx.robotY = m_lastPose.y();
			ctx.localCells = m_opts.localCells;
			ctx.pngLegend = m_opts.pngLegend;
			t->writeOutputs(map, ctx, files);
		}
		else
		{
			// Any other map of the .ini: MRPT's own representation + the serialized object.
			const auto before = [&] {
				std::set<std::string> n;
				for (const auto& de : fs::directory_iterator(dir)) n.insert(de.path().filename().string());
				return n;
			}();
			map.saveMetricMapRepresentationToFile(base);
			gam::maps::writeSerializedGz(map, base + ".map.gz");
			for (const auto& de : fs::directory_iterator(dir))
			{
				const auto n = de.path().filename().string();
				if (!before.count(n) && de.is_regular_file()) files.push_back(n);
			}
		}
	}
}

void Mapper::writeSnapshot(const std::string& dir) const
{
	fs::create_directories(dir);
	for (size_t i = 0; i < m_specs.size(); i++)
		if (const auto* g = dynamic_cast<const mrpt::maps::COccupancyGridMap2D*>(m_maps.maps[i].get()))
		{
			const std::string L = m_specs[i].label;
			gam::maps::writeRosMap(*g, dir + "/" + L + ".yaml", dir + "/" + L + ".pgm", L + ".pgm");
		}
}

}  // namespace gam::mapper
