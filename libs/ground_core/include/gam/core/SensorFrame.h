// Ground-aware mapping for MRPT
// One 3D observation as the pure core reads it: a range image with its
// intrinsics, or a list of sensor-frame points, and where the sensor was. The
// MRPT plugin fills it from an observation without copying the samples
// (gam/maps/ObservationAdapters.h); binSensorFrame() turns it into 2.5D bins.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <limits>
#include <string_view>

#include "gam/core/DepthProjector.h"
#include "gam/core/ElevationGrid.h"

namespace gam
{
struct SensorFrame
{
	/** Sensor -> map frame (the sensor frame is MRPT's: +X forward, +Y left, +Z up). */
	RigidTransform sensor_to_map;
	/** The sensor's position in the map frame (double: the ISM's reference). */
	Eigen::Vector3d sensor_position = Eigen::Vector3d::Zero();
	/** The sensor's label (camera_model = auto reads it); may be empty. */
	std::string_view sensor_label;
	/** The sensor's own range limit, applied on top of the projection filter. */
	float max_range = std::numeric_limits<float>::infinity();

	/** A range image (has_image) or `point_count` points x/y/z in the sensor frame. */
	bool has_image = false;
	RangeImageView image;
	PinholeIntrinsics intrinsics;
	const float* x = nullptr;
	const float* y = nullptr;
	const float* z = nullptr;
	size_t point_count = 0;
};

/** Bins sensor-frame points (range limits on the sensor-frame norm, z band in
 * the map frame) into `out`; non-finite points are skipped. Returns the
 * number binned. */
size_t binPoints(
	const float* xs, const float* ys, const float* zs, size_t n, const RigidTransform& sensorToMap,
	const ProjectionFilter& f, const ElevationGrid& grid, BinnedPoints& out);

/** Where binSensorFrame cuts `frame`'s samples: the nearer of the filter's
 * max_range and the frame's [m], on the depth along the sensor's x axis for a
 * depth image, on the range otherwise. */
inline float sampleRangeLimit(const SensorFrame& frame, const ProjectionFilter& f)
{
	return std::min(f.max_range, frame.max_range);
}

/** Bins every valid sample of `frame` (up to sampleRangeLimit) into `out`.
 * Throws std::invalid_argument if its image and intrinsics disagree. */
size_t binSensorFrame(
	const SensorFrame& frame, const ProjectionFilter& f, const ElevationGrid& grid, DepthProjector& projector,
	BinnedPoints& out);

}  // namespace gam
