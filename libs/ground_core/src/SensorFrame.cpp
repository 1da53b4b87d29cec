#include "gam/core/SensorFrame.h"

#include <algorithm>

namespace gam
{
size_t binPoints(
	const float* xs, const float* ys, const float* zs, size_t n, const RigidTransform& T, const ProjectionFilter& f,
	const ElevationGrid& grid, BinnedPoints& out)
{
	size_t binned = 0;
	const bool rangeCheck = f.max_range < std::numeric_limits<float>::max() || f.min_range > 0;
	const float min2 = f.min_range * f.min_range, max2 = f.max_range * f.max_range;
	for (size_t i = 0; i < n; i++)
	{
		const Eigen::Vector3f p(xs[i], ys[i], zs[i]);
		if (!p.allFinite()) continue;
		if (rangeCheck)
		{
			const float r2 = p.squaredNorm();
			if (r2 < min2 || r2 > max2) continue;
		}
		const Eigen::Vector3f q = T.R * p + T.t;
		if (!(q.z() >= f.z_min && q.z() <= f.z_max)) continue;
		if (grid.binPoint(q.x(), q.y(), q.z(), out)) binned++;
	}
	return binned;
}

size_t binSensorFrame(
	const SensorFrame& frame, const ProjectionFilter& filter, const ElevationGrid& grid, DepthProjector& projector,
	BinnedPoints& out)
{
	ProjectionFilter f = filter;
	f.max_range = sampleRangeLimit(frame, filter);
	if (frame.has_image) return projector.project(frame.image, frame.intrinsics, frame.sensor_to_map, f, grid, out);
	return binPoints(frame.x, frame.y, frame.z, frame.point_count, frame.sensor_to_map, f, grid, out);
}

}  // namespace gam
