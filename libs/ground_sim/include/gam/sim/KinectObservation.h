// Ground-aware mapping for MRPT -- MRPT glue of the simulator (header-only):
// its Kinect frames and Leddar scans as MRPT observations.
// The ground_sim library itself is pure; this header needs mrpt::obs, so only
// programs that link MRPT include it (gam-simulate, the navigation example).
#pragma once

#include <mrpt/obs/CObservation2DRangeScan.h>
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
 * on the robot, labelled defaultCameraLabel(kinect.model) ("KINECT" for the
 * Kinect One). `validPixels` (optional) gets the number of non-zero pixels. */
inline mrpt::obs::CObservation3DRangeScan::Ptr toKinectObservation(
	const KinectParams& kinect, const DepthFrame& fr, const mrpt::poses::CPose3D& sensorPose,
	size_t* validPixels = nullptr)
{
	auto k = mrpt::obs::CObservation3DRangeScan::Create();
	k->sensorLabel = defaultCameraLabel(kinect.model);
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

/** A simulated Leddar scan as MRPT's CObservation2DRangeScan: one range per
 * segment (0 and invalid where no echo), MRPT's angle convention
 * (rightToLeft, aperture = the horizontal field of view), `sensorPose` on the robot. */
inline mrpt::obs::CObservation2DRangeScan::Ptr toLeddarObservation(
	const LeddarParams& leddar, const LeddarScan& ls, const mrpt::poses::CPose3D& sensorPose)
{
	auto l = mrpt::obs::CObservation2DRangeScan::Create();
	l->sensorLabel = "LEDDAR";
	l->aperture = float(leddar.hfov_deg * M_PI / 180.0);
	l->rightToLeft = true;
	l->maxRange = float(leddar.max_range);
	l->stdError = float(leddar.sigma);
	l->beamAperture = float(leddar.hfov_deg / leddar.segments * M_PI / 180.0);
	l->sensorPose = sensorPose;
	l->resizeScan(size_t(leddar.segments));
	for (int s = 0; s < leddar.segments; s++)
	{
		l->setScanRange(size_t(s), ls.valid[size_t(s)] ? ls.range[size_t(s)] : 0.0f);
		l->setScanRangeValidity(size_t(s), ls.valid[size_t(s)]);
	}
	return l;
}

}  // namespace gam::sim
