// Shared by the libFuzzer targets: a tiny synthetic depth frame, and the maps.
#pragma once

#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/COctoMapGrid2D.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <cmath>
#include <memory>
#include <vector>

namespace gamfuzz
{
/** A 32x24 depth frame of a floor 1 m below a camera pitched 30 deg down, with a step. */
inline mrpt::obs::CObservation3DRangeScan::Ptr tinyFrame()
{
	auto o = mrpt::obs::CObservation3DRangeScan::Create();
	const int W = 32, H = 24;
	o->hasRangeImage = true;
	o->range_is_depth = true;
	o->rangeUnits = 0.001f;
	o->maxRange = 5;
	o->sensorPose = mrpt::poses::CPose3D(0, 0, 1.0, 0, 30 * M_PI / 180, 0);
	o->cameraParams.ncols = W;
	o->cameraParams.nrows = H;
	o->cameraParams.setIntrinsicParamsFromValues(24, 24, 15.5, 11.5);
	o->rangeImage_setSize(H, W);
	const double p = 30 * M_PI / 180;
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			// Ray (1, ky, kz) in the sensor frame; its z in the world after the pitch.
			const double kz = (11.5 - r) / 24.0;
			const double dz = -std::sin(p) + kz * std::cos(p), dx = std::cos(p) + kz * std::sin(p);
			double D = dz < -1e-3 ? 1.0 / -dz : 0;  // depth along the optical axis
			if (D * dx > 2.0) D = D * 0.97;         // a 3 cm step beyond 2 m
			o->rangeImage(r, c) = (D > 0 && D < 5) ? uint16_t(std::lround(D * 1000)) : 0;
		}
	return o;
}

inline std::vector<std::shared_ptr<mrpt::maps::CMetricMap>> freshMaps()
{
	mrpt::maps::registerGroundAwareMaps();
	mrpt::maps::registerBaselineMaps();
	auto ga = std::make_shared<mrpt::maps::CGroundAwareOccupancyGrid>(-2, 2, -2, 2, 0.05);
	auto o = ga->groundOptions();
	o.pipeline.m_x = o.pipeline.m_y = 100;
	o.pipeline.rrt.iterations = 100;
	ga->setGroundOptions(o);
	return {
		std::make_shared<mrpt::maps::CElevation25DMap>(-5, 5, -5, 5, 0.1), ga,
		std::make_shared<mrpt::maps::CHeightBandOccupancyGrid>(-2, 2, -2, 2, 0.05),
		std::make_shared<mrpt::maps::COctoMapGrid2D>(-2, 2, -2, 2, 0.05)};
}
}  // namespace gamfuzz
