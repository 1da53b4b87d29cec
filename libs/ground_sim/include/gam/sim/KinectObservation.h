// Ground-aware mapping for MRPT -- MRPT glue of the simulator (header-only).
// The ground_sim library itself is pure; this header needs mrpt::obs, so only
// programs that link MRPT include it (gam-simulate, the navigation example).
#pragma once

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "gam/sim/Sensors.h"

namespace gam::sim
{
/** A simulated Kinect frame as MRPT's CObservation3DRangeScan: depth along +X
 * in millimetres (0 = no return), pinhole intrinsics of `kinect`, `sensorPose`
 * on the robot. `validPixels` (optional) gets the number of non-zero pixels. */
inline mrpt::obs::CObservation3DRangeScan::Ptr toKinectObservation(
	const KinectParams& kinect, const DepthFrame& fr, const mrpt::poses::CPose3D& sensorPose,
	size_t* validPixels = nullptr)
{
	auto k = mrpt::obs::CObservation3DRangeScan::Create();
	k->sensorLabel = "KINECT";
	k->hasRangeImage = true;
	k->range_is_depth = true;
	k->rangeUnits = 0.001f;
	k->maxRange = float(kinect.max_range);
	k->stdError = float(kinect.sigma(2.0, 0.0));
	k->sensorPose = sensorPose;
	k->cameraParams.ncols = uint32_t(fr.width);
	k->cameraParams.nrows = uint32_t(fr.height);
	k->cameraParams.setIntrinsicParamsFromValues(kinect.fx(), kinect.fy(), kinect.cx(), kinect.cy());
	k->cameraParamsIntensity = k->cameraParams;
	k->rangeImage_setSize(fr.height, fr.width);
	size_t valid = 0;
	for (int r = 0; r < fr.height; r++)
		for (int c = 0; c < fr.width; c++)
		{
			const float d = fr.depth[fr.idx(r, c)];
			const long u = d > 0 ? std::lround(d / 0.001) : 0;
			k->rangeImage(r, c) = uint16_t(std::clamp(u, 0L, 65535L));
			valid += u > 0;
		}
	if (validPixels) *validPixels = valid;
	return k;
}

}  // namespace gam::sim
