// libFuzzer target: .ini text -> gam::mapper::loadMapDefinitions (the mapper's
// validated TSetOfMetricMapInitializers loader, every option table) ->
// CMultiMetricMap -> one tiny depth frame into every map. Sizes are bounded here
// (not by the loaders, which allow grids up to 2^28 cells): maps are only built
// when all are this project's and small, and the frame is only inserted with cheap
// iteration counts, so each input runs in milliseconds. Exceptions are the expected
// answer to bad options; crashes, sanitizer reports, leaks and hangs are bugs.
#include <gam/mapper/Mapper.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>

#include <cmath>
#include <cstdint>
#include <exception>
#include <string>

#include "fuzz_common.h"

using namespace mrpt::maps;

namespace
{
bool small(double x0, double x1, double y0, double y1, double res)
{
	return (x1 - x0) / res * (y1 - y0) / res <= double(1 << 20);
}

/** True if every map is one of ours, small, and cheap to run. */
bool bounded(const TSetOfMetricMapInitializers& inits)
{
	for (const auto& i : inits)
	{
		if (const auto* g = dynamic_cast<const CGroundAwareOccupancyGrid::TMapDefinition*>(i.get()))
		{
			const gam::PipelineParams& o = g->groundOpts.pipeline;
			if (!small(g->min_x, g->max_x, g->min_y, g->max_y, g->resolution) || double(o.m_x) * o.m_y > 1 << 18 ||
				o.rrt.iterations > 2000 || o.rrt.ransac_iterations > 2000 || o.idw.radius_cells > 5 ||
				o.rrt.seed_attempts > 10)
				return false;
		}
		else if (const auto* h = dynamic_cast<const CHeightBandOccupancyGrid::TMapDefinition*>(i.get()))
		{
			if (!small(h->min_x, h->max_x, h->min_y, h->max_y, h->resolution)) return false;
		}
		else if (const auto* c = dynamic_cast<const COctoMapGrid2D::TMapDefinition*>(i.get()))
		{
			if (!small(c->min_x, c->max_x, c->min_y, c->max_y, c->resolution) || c->octoOpts.voxel_size < 0.02 ||
				c->octoOpts.max_range > 20)
				return false;
		}
		else if (const auto* e = dynamic_cast<const CElevation25DMap::TMapDefinition*>(i.get()))
		{
			if (!small(e->min_x, e->max_x, e->min_y, e->max_y, e->resolution) || e->insertionOpts.idw.radius_cells > 5)
				return false;
		}
		else
			return false;  // stock MRPT maps: their own sizes are not ours to bound
	}
	return true;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	if (size > 8192) return 0;
	static const auto frame = gamfuzz::tinyFrame();
	mrpt::maps::registerGroundAwareMaps();
	try
	{
		mrpt::config::CConfigFileMemory cfg(std::string(reinterpret_cast<const char*>(data), size));
		TSetOfMetricMapInitializers inits;
		std::vector<gam::mapper::MapSpec> specs;
		std::vector<std::string> warnings;
		gam::mapper::loadMapDefinitions(cfg, "map", inits, specs, &warnings);
		if (inits.size() > 4 || !bounded(inits)) return 0;
		CMultiMetricMap mm;
		mm.setListOfMaps(inits);
		for (auto& m : mm.maps)
		{
			try
			{
				m->insertObservation(*frame);
			}
			catch (const std::exception&)
			{
			}
		}
	}
	catch (const std::exception&)
	{
	}
	return 0;
}
