#include "gam/core/InverseSensorModel.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace gam
{
void IsmParams::validate() const { checkParamRanges(*this, ""); }

namespace ism
{
double voxelDensity(uint32_t count, double span, double resolution)
{
	const double h = std::max(span, resolution);
	return double(count) / (resolution * resolution * h);
}
double densityConfidence(double rho, const IsmParams& p) { return 1.0 / (1.0 + std::exp(-(p.K_n * rho - p.d_min))); }
double obstacleProbability(double pr, const IsmParams& p) { return 0.5 + 0.5 * p.K_m * pr; }
double groundProbability(double d, const IsmParams& p) { return 0.5 - p.K_g * std::exp(-d * d / (2.0 * p.sigma2)); }
double binomialTail(uint32_t n, double p, uint32_t k)
{
	if (k == 0) return 1.0;
	if (k > n || !(p > 0)) return 0.0;
	if (p >= 1) return 1.0;
	// 1 - sum_{i<k} C(n,i) p^i (1-p)^(n-i), the terms by recurrence; the tail
	// is compared with ~1e-3, far above the round-off of the sum.
	double term = std::pow(1.0 - p, double(n)), below = 0;
	const double ratio = p / (1.0 - p);
	for (uint32_t i = 0; i < k; i++)
	{
		below += term;
		term *= double(n - i) / double(i + 1) * ratio;
	}
	return std::max(0.0, 1.0 - below);
}
float kthSmallest(float* v, size_t n, size_t k)
{
	size_t lo = 0, hi = n;  // v[k] lies in [lo, hi)
	for (int round = 0; hi - lo > 16 && round < 64; round++)
	{
		// Median of three as the pivot: an element of the range.
		const float a = v[lo], b = v[lo + (hi - lo) / 2], c = v[hi - 1];
		const float pivot = std::max(std::min(a, b), std::min(std::max(a, b), c));
		// Branch-free Lomuto passes: [lo, less) < pivot, [less, upTo) == pivot.
		size_t less = lo;
		for (size_t i = lo; i < hi; i++)
		{
			const float x = v[i];
			v[i] = v[less];
			v[less] = x;
			less += x < pivot;
		}
		size_t upTo = less;
		for (size_t i = less; i < hi; i++)
		{
			const float x = v[i];
			v[i] = v[upTo];
			v[upTo] = x;
			upTo += x <= pivot;
		}
		if (k < less)
			hi = less;
		else if (k < upTo)
			return pivot;
		else
			lo = upTo;
	}
	std::nth_element(v + lo, v + k, v + hi);
	return v[k];
}
}  // namespace ism

double InverseSensorModel::rangeFrom(const Eigen::Vector3d& sensor, double x, double y, double z)
{
	const double dx = x - sensor.x(), dy = y - sensor.y(), dz = z - sensor.z();
	return std::sqrt(dx * dx + dy * dy + dz * dz);
}

double InverseSensorModel::groundBand(const Eigen::Vector3d& sensor, double h, double x, double y, double z) const
{
	if (m_params.noise_sigmas <= 0) return m_params.d_pth;
	const double r = rangeFrom(sensor, x, y, z);
	if (r < 1e-3) return m_params.d_pth;
	// The floor's vertical scatter measured in this frame at this range, if
	// enough floor was seen there; else the sensor model.
	const size_t bin = size_t(r / m_params.floor_noise_bin);
	if (bin < m_floorNoise.size() && m_floorNoise[bin] >= 0)
		return m_params.d_pth + m_params.noise_sigmas * double(m_floorNoise[bin]);
	const double sd = m_params.depth_noise_c0 + m_params.depth_noise_c2 * r * r;
	const double sinElev = std::clamp(std::abs(h) / r, 0.0, 1.0);
	return m_params.d_pth + m_params.noise_sigmas * sd * sinElev;
}

void InverseSensorModel::measureFloorNoise(
	const ElevationGrid& frame, const GroundDetection& det, const Eigen::Vector3d& sensor)
{
	// Floor cells (mean within d_pth of the ground, a few samples) hold the
	// vertical scatter of the sensor at their range: their sample std. The
	// median per range bin is robust to the odd obstacle cell among them.
	const GridGeometry& g = frame.geometry();
	const size_t nb = size_t(std::ceil((m_maxRange + 1.0) / m_params.floor_noise_bin));
	m_floorNoise.assign(nb, -1.f);
	m_floorOffset.assign(nb, -1.f);
	m_offsetValue.clear();
	// The two measurements are separate switches: the floor offset (tau) is
	// measured without the noise, and the other way round.
	if ((!m_params.measure_floor_noise && !m_params.measure_floor_offset) || m_params.noise_sigmas <= 0) return;
	m_noiseBin.clear();
	m_noiseValue.clear();
	for (uint32_t idx : frame.observedCells())
	{
		const ElevationCell& c = frame.cell(idx);
		if (c.count < 4) continue;
		const int cx = int(idx % uint32_t(g.nx)), cy = int(idx / uint32_t(g.nx));
		const double x = g.cx(cx), y = g.cy(cy);
		const int block = (cy / m_blockCells) * m_bnx + (cx / m_blockCells);
		const Plane& pl = choosePlane(det, c, x, y, block);
		if (std::abs(pl.signedDistance(x, y, c.mean())) > m_params.d_pth) continue;
		const size_t bin = size_t(rangeFrom(sensor, x, y, c.mean()) / m_params.floor_noise_bin);
		if (bin < nb)
		{
			m_noiseBin.push_back(uint32_t(bin));
			m_noiseValue.push_back(std::sqrt(c.variance()));
			m_offsetValue.push_back(float(std::abs(pl.signedDistance(x, y, c.mean()))));
		}
	}
	// Group the samples by bin (stable counting sort), then the median of each.
	m_noiseBinStart.assign(nb + 1, 0);
	for (uint32_t b : m_noiseBin) m_noiseBinStart[b + 1]++;
	for (size_t b = 0; b < nb; b++) m_noiseBinStart[b + 1] += m_noiseBinStart[b];
	m_noiseSorted.resize(m_noiseValue.size());
	m_offsetSorted.resize(m_offsetValue.size());
	for (size_t i = 0; i < m_noiseBin.size(); i++)
	{
		const uint32_t at = m_noiseBinStart[m_noiseBin[i]]++;
		m_noiseSorted[at] = m_noiseValue[i];
		m_offsetSorted[at] = m_offsetValue[i];
	}
	// m_noiseBinStart[b] is now the end of bin b (= the start of bin b + 1).
	for (size_t b = 0; b < nb; b++)
	{
		const uint32_t begin = b == 0 ? 0 : m_noiseBinStart[b - 1], end = m_noiseBinStart[b];
		const size_t n = end - begin;
		if (n < size_t(std::max(1, m_params.floor_noise_min_cells))) continue;
		float* v = m_noiseSorted.data() + begin;
		if (m_params.measure_floor_noise)
		{
			m_floorNoise[b] = ism::kthSmallest(v, n, n / 2);
		}
		// The cells' means around the plane: 1.4826 x the median |distance| is
		// their std for a normal spread (robust to the odd bump among them).
		float* o = m_offsetSorted.data() + begin;
		m_floorOffset[b] = 1.4826f * ism::kthSmallest(o, n, n / 2);
	}
}

double InverseSensorModel::floorOffset(const Eigen::Vector3d& sensor, double x, double y, double z) const
{
	if (!m_params.measure_floor_offset) return -1;
	const size_t bin = size_t(rangeFrom(sensor, x, y, z) / m_params.floor_noise_bin);
	return bin < m_floorOffset.size() ? double(m_floorOffset[bin]) : -1;
}

VoxelClass InverseSensorModel::classify(
	const ElevationCell& c, double x, double y, const Plane& pl, double band, double& dMean, double floorOffset) const
{
	const double dTop = pl.signedDistance(x, y, c.z_max);
	const double dBot = pl.signedDistance(x, y, c.z_min);
	dMean = pl.signedDistance(x, y, c.mean());
	const double th = band;
	if (dTop < -th) return VoxelClass::Drop;
	if (dTop > th) return VoxelClass::Obstacle;
	// Top within the band; a bottom far below it is the edge of a hole.
	if (dBot < -th) return VoxelClass::Drop;
	// Every sample is inside the band, but their mean may not be: the noise
	// part of the band shrinks with sqrt(N) for the mean of N samples, the
	// d_pth part (plane error, floor unevenness) does not.
	if (m_params.mean_test && c.count > 1 && th > m_params.d_pth)
	{
		// The band below is never narrower than d_pth, nor, with the measured
		// floor offset, than min(d_pth, traversable_step): a mean within that
		// is ground without its square roots (most floor cells; the same
		// class, the bound is exact).
		const bool measuredOffset = floorOffset >= 0 && m_params.noise_sigmas > 0;
		const double narrowest = measuredOffset ? std::min(m_params.d_pth, m_params.traversable_step) : m_params.d_pth;
		if (std::abs(dMean) <= narrowest) return VoxelClass::Ground;
		double meanBand = m_params.d_pth + (th - m_params.d_pth) / std::sqrt(double(c.count));
		if (measuredOffset)
		{
			// Both parts measured on this frame's floor: sigma (one sample) from
			// the band, tau (a cell's mean) from the floor cells. Never wider
			// than the d_pth form (a floor too rough to measure keeps that).
			const double k = m_params.noise_sigmas, sigma = (th - m_params.d_pth) / k;
			const double measured = k * std::sqrt(floorOffset * floorOffset + sigma * sigma / double(c.count));
			meanBand = std::min(meanBand, std::max(measured, m_params.traversable_step));
		}
		if (dMean > meanBand) return VoxelClass::Obstacle;
		if (dMean < -meanBand) return VoxelClass::Drop;
	}
	return VoxelClass::Ground;
}

void InverseSensorModel::buildSupport(const GridGeometry& g, const GroundDetection& det)
{
	const int B = m_blockCells;
	m_bnx = (g.nx + B - 1) / B;
	m_bny = (g.ny + B - 1) / B;
	m_support.assign(size_t(m_bnx) * size_t(m_bny), 0);
	if (!m_params.local_planes || det.planes.size() < 2) return;
	const double bres = B * g.resolution;
	const int rb = int(std::ceil(m_params.plane_support_radius / bres));
	// This frame's patches, then the remembered ones (PatchMemory) where none
	// of this frame's applies: what the frame fitted itself decides there.
	const int firstRemembered = det.remembered_from > 0 ? int(det.remembered_from) : int(det.planes.size());
	const uint8_t own = uint8_t(((1u << firstRemembered) - 1u) & ~1u);
	for (int pass = 0; pass < 2; pass++)
		for (const GroundNode& n : det.nodes)
		{
			if (n.plane_id < 1 || (n.plane_id >= firstRemembered) != (pass == 1)) continue;
			const int bx = int(std::floor((n.x - g.x_min) / bres)), by = int(std::floor((n.y - g.y_min) / bres));
			for (int yy = std::max(0, by - rb); yy <= std::min(m_bny - 1, by + rb); yy++)
				for (int xx = std::max(0, bx - rb); xx <= std::min(m_bnx - 1, bx + rb); xx++)
				{
					uint8_t& bits = m_support[size_t(yy) * size_t(m_bnx) + size_t(xx)];
					if (pass == 0 || !(bits & own)) bits |= uint8_t(1u << n.plane_id);
				}
		}
}

const Plane& InverseSensorModel::choosePlane(
	const GroundDetection& det, const ElevationCell& c, double x, double y, int block) const
{
	const uint8_t bits = m_support.empty() ? 0 : m_support[size_t(block)];
	if (!bits) return det.planes.front();
	// Among the main plane and the patches that apply here, the one the voxel
	// fits best: a ramp voxel sits on the ramp, a box stands on both.
	const Plane* best = &det.planes.front();
	auto cost = [&](const Plane& pl) {
		return std::max(std::abs(pl.signedDistance(x, y, c.z_max)), std::abs(pl.signedDistance(x, y, c.z_min)));
	};
	double bestCost = cost(*best);
	for (size_t k = 1; k < det.planes.size(); k++)
		if (bits & (1u << k))
		{
			const double cst = cost(det.planes[k]);
			if (cst < bestCost)
			{
				bestCost = cst;
				best = &det.planes[k];
			}
		}
	return *best;
}

float InverseSensorModel::obstacleEvidence(const ElevationCell& c, double resolution) const
{
	const double rho = ism::voxelDensity(c.count, c.span(), resolution);
	return float(ism::obstacleProbability(ism::densityConfidence(rho, m_params), m_params));
}

bool InverseSensorModel::rayBlocked(
	const ElevationGrid& frame, const Plane& pl, const Eigen::Vector3d& sensor, double hs, double ex, double ey) const
{
	// Walk back from the crossing (ex, ey) towards the sensor, half a cell at a
	// time, to the first cell this frame observed: the ray passed over it at
	// height hs (1 - rho / rhoC) above the plane (rho: 2D distance from the
	// sensor). An obstacle there whose top reaches that height stopped it.
	const GridGeometry& g = frame.geometry();
	const double dx = ex - sensor.x(), dy = ey - sensor.y();
	const double rhoC = std::sqrt(dx * dx + dy * dy);
	if (!(rhoC > 0)) return false;
	const int steps = int(rhoC / (0.5 * g.resolution));
	for (int k = 0; k < steps; k++)
	{
		const double f = 1.0 - double(k) / steps;  // rho / rhoC
		const double x = sensor.x() + f * dx, y = sensor.y() + f * dy;
		const int cx = g.ix(x), cy = g.iy(y);
		if (!g.inside(cx, cy)) continue;
		const VoxelClass c = m_class[g.index(cx, cy)];
		if (c == VoxelClass::None) continue;
		if (c != VoxelClass::Obstacle) return false;
		return pl.signedDistance(x, y, frame.cell(g.index(cx, cy)).z_max) >= hs * (1.0 - f);
	}
	return false;
}

bool InverseSensorModel::smeared(
	const ElevationGrid& frame, uint32_t cell, uint32_t beyond, bool drop, const Eigen::Vector3d& sensor) const
{
	const GridGeometry& g = frame.geometry();
	const ElevationCell& v = frame.cell(cell);
	const int cx = int(cell % uint32_t(g.nx)), cy = int(cell / uint32_t(g.nx));
	const double x = g.cx(cx), y = g.cy(cy);
	const double zv = drop ? v.z_min : v.z_max;  // its extreme sample
	const double dx = x - sensor.x(), dy = y - sensor.y(), dz = zv - sensor.z();
	const double rho = std::sqrt(dx * dx + dy * dy);
	if (!(rho > 0)) return false;
	// One sample's range sigma at this slant range, both parts (taking the
	// slant range for the depth overstates it by at most 1 / cos of the
	// half field of view), and its horizontal and vertical shares.
	const double r = std::sqrt(rho * rho + dz * dz);
	const double sigma = std::hypot(m_camera.independent(r, m_fx), m_camera.correlated(r, m_fx));
	const double k = m_params.noise_sigmas, reach = k * sigma;
	const double sigma2d = sigma * rho / r, reach2d = reach * rho / r, rise = reach * std::abs(dz) / r;
	const double res = g.resolution, step = 0.5 * res;
	if (!(sigma2d > 0) || reach2d + step < res) return false;  // it never reaches the next cell
	// Of a surface's samples at a cell's centre, the share its range noise
	// leaves in that cell, and the share it moves into a cell d away.
	const auto phi = [](double u) { return 0.5 * std::erfc(-u / std::sqrt(2.0)); };
	double stay = -1;  // computed at the first candidate cell
	// An obstacle's samples come toward the sensor, in front of its face; a
	// drop's (the face of a step down, a hole's far wall) go away from it,
	// into the floor beyond its edge.
	const double sign = drop ? -1.0 : 1.0;
	const double ux = sign * dx / rho, uy = sign * dy / rho;
	const VoxelClass same = drop ? VoxelClass::Drop : VoxelClass::Obstacle;
	// Where the frame's samples end (setCameraRangeLimit): `limit` beyond
	// this cell's centre, horizontally, along the ray through its extreme
	// sample (a sample's error moves it along its ray). An obstacle's walk
	// goes away from the sensor, toward the limit; a surface beyond it returns
	// only the samples its noise brings nearer, and of a cell near it the
	// limit cuts the samples its noise moves past it.
	double limit = std::numeric_limits<double>::infinity();
	if (!drop && std::isfinite(m_rangeLimit))
	{
		// This sample's depth (or range), and what a metre along its ray adds.
		const bool onRange = m_rangeAxis.isZero();
		const double along = onRange ? r : Eigen::Vector3d(dx, dy, dz).dot(m_rangeAxis);
		const double perMetre = along / r;
		if (perMetre > 0) limit = (m_rangeLimit - along) / perMetre * rho / r;
	}
	uint32_t last = cell;
	bool seenBefore = false;  // a surface as high seen inside the limit, on the way to it
	for (double t = res; t <= reach2d + step + 1e-9; t += step)
	{
		const int qx = g.ix(x + t * ux), qy = g.iy(y + t * uy);
		if (!g.inside(qx, qy)) return false;
		const uint32_t q = uint32_t(g.index(qx, qy));
		if (q == last) continue;
		last = q;
		const VoxelClass qc = m_class[q];
		if (qc == VoxelClass::None)
		{
			// Not seen in this frame: look on. Past the limit with nothing seen
			// on the way: these samples may all be those a surface beyond the
			// limit returned (a wall just out of range).
			if (t > limit && !seenBefore) return true;
			continue;
		}
		// A cell beyond the range the map takes evidence from (max_range, or
		// the camera's range of trust) was seen but judged nowhere: its
		// samples moved as any others, and a wall that straddles that range
		// puts its noise into the judged cells in front of it.
		const bool unjudged = qc == VoxelClass::OutOfRange;
		if (qc != same && !unjudged) return false;  // anything else between them: a separate object
		const ElevationCell& w = frame.cell(q);
		// As high (deep) as this cell's extreme sample, less the vertical share
		// of the displacement. An unjudged cell that is not may be floor, which
		// would make this cell an object of its own: kept.
		if (drop ? w.z_min - rise > v.z_min : w.z_max + rise < v.z_max)
		{
			if (unjudged) return false;
			continue;
		}
		const double d = std::hypot(g.cx(qx) - x, g.cy(qy) - y);
		// The share of that cell's samples its noise leaves there, less those
		// it moves past the limit; a cell wholly inside it is a surface seen
		// in its own right between this one and the limit.
		if (stay < 0) stay = 2.0 * phi(0.5 * res / sigma2d) - 1.0;
		const double room = limit - d;
		const double stayHere = room >= 0.5 * res ? stay : phi(room / sigma2d) - phi(-0.5 * res / sigma2d);
		seenBefore |= room >= 0.5 * res;
		if (!(stayHere > 0)) continue;
		// (An unjudged cell has no band to count beyond: all its samples, of
		// which a wall's lowest few centimetres are a few per cent.)
		const uint32_t wBeyond = m_tailCell[q] ? m_tailCount[q] : w.count;
		// This cell's samples are that cell's if they are no more than its
		// noise puts here (expected lambda, and noise_sigmas Poisson
		// deviations above it) and nearer that count than the one a surface
		// of its own, as dense as that cell, would give (in Poisson
		// deviations of each): a low object's top spread over a few cells is
		// as dense in each, a wall's samples in front of it are not.
		const double n = double(beyond), nw = double(wBeyond);
		if (!(n < nw)) continue;
		const double moved = phi((d + 0.5 * res) / sigma2d) - phi((d - 0.5 * res) / sigma2d);
		const double lambda = nw * moved / stayHere;
		if (!(lambda > 0) || n > lambda + k * std::sqrt(lambda)) continue;
		if (std::abs(n - lambda) / std::sqrt(lambda) < (nw - n) / std::sqrt(nw)) return true;
	}
	return false;
}

void InverseSensorModel::countTailSamples(const ElevationGrid& frame, const BinnedPoints& samples, IsmStats& stats)
{
	// One pass over the frame's samples: each candidate cell counts those
	// below its low threshold or above its high one that the 3-sigma rule
	// kept (the kept ones are exactly those in [z_min, z_max] of the cell).
	const ConstSpan<uint32_t> cells = samples.cells();
	const ConstSpan<float> zs = samples.heights();
	// Most samples lie in other cells (thresholds -inf / +inf): one byte per
	// cell tells, where the two thresholds are 8 bytes, far apart.
	for (const TailCandidate& d : m_tailCandidates) m_tailCell[d.cell] = 1;
	const size_t listed = samplesInMarkedCells(samples, m_tailCell.data(), m_tailSamples, true);
	for (size_t k = 0; k < listed; k++)
	{
		const uint32_t i = m_tailSamples[k];
		const uint32_t c = cells[i];
		const float z = zs[i];
		if ((z < m_tailLo[c] && z >= frame.cell(c).z_min) || (z > m_tailHi[c] && z <= frame.cell(c).z_max))
			m_tailCount[c]++;
	}
	const double alpha = ism::normalTail(m_params.noise_sigmas);
	const bool smear = smearTest();
	// The counts stay until clearTailCandidates(): range_smear reads them.
	for (const TailCandidate& d : m_tailCandidates)
	{
		const uint32_t k = m_tailCount[d.cell];
		const ElevationCell& c = frame.cell(d.cell);
		if (d.kind == TailKind::Deep || d.kind == TailKind::Raised)
		{
			// A ground cell the count makes a drop (deep) or an obstacle (raised).
			const bool drop = d.kind == TailKind::Deep;
			if (k < minPoints() || ism::binomialTail(c.count, double(d.p0), k) >= alpha) continue;
			// Its ground evidence stays if range_smear takes this back.
			m_class[d.cell] = drop ? VoxelClass::Drop : VoxelClass::Obstacle;
			hold(Held{d.cell, k, drop, true}, smear, frame, stats);
			continue;
		}
		// An obstacle or a drop judged by its extreme sample: it takes as many
		// samples beyond the band as any other (a lone spike among floor
		// samples is no obstacle, and casts no ray: a drop that counts casts
		// its ray).
		const bool drop = d.kind == TailKind::Below;
		if (k < minPoints())
		{
			stats.sparse++;
			continue;
		}
		hold(Held{d.cell, k, drop, false}, smear, frame, stats);
	}
}

void InverseSensorModel::hold(const Held& h, bool smear, const ElevationGrid& frame, IsmStats& stats)
{
	if (smear)
		m_held.push_back(h);
	else
		give(h, frame, stats);
}

void InverseSensorModel::give(const Held& h, const ElevationGrid& frame, IsmStats& stats)
{
	if (h.deep)
	{
		stats.ground--;
		(h.drop ? stats.deep_drops : stats.raised_obstacles)++;
	}
	(h.drop ? stats.drop : stats.obstacle)++;
	put(h.cell, obstacleEvidence(frame.cell(h.cell), frame.geometry().resolution));
	// A drop that counts casts its ray (it takes min_obstacle_points, as it counts).
	if (h.drop && m_params.drop_rays) m_dropVoxels.push_back(h.cell);
}

void InverseSensorModel::clearTailCandidates()
{
	for (const TailCandidate& d : m_tailCandidates)
	{
		m_tailLo[d.cell] = -std::numeric_limits<float>::infinity();
		m_tailHi[d.cell] = std::numeric_limits<float>::infinity();
		m_tailCount[d.cell] = 0;
		m_tailCell[d.cell] = 0;
	}
	m_tailCandidates.clear();
}

void InverseSensorModel::compute(
	const ElevationGrid& frame, const GroundDetection& det, const Eigen::Vector3d& sensor, double maxRange,
	IsmStats& stats, const BinnedPoints* samples)
{
	if (!(maxRange > 0) || !std::isfinite(maxRange))
		throw std::invalid_argument("ISM: the sensor's max range must be > 0 (got " + std::to_string(maxRange) + ")");
	m_maxRange = maxRange;
	stats = IsmStats{};
	const GridGeometry& g = frame.geometry();
	if (m_evidence.size() != g.cellCount())
	{
		m_evidence.assign(g.cellCount(), 0.5f);
		m_class.assign(g.cellCount(), VoxelClass::None);
		m_evidenceCells.clear();
		m_classCells.clear();
		// Each list holds a cell at most once: with the capacity of the whole
		// grid, no frame ever needs to grow them (no per-frame allocation).
		m_evidenceCells.reserve(g.cellCount());
		m_classCells.reserve(g.cellCount());
		m_dropVoxels.reserve(g.cellCount());
		m_noiseBin.reserve(g.cellCount());
		m_noiseValue.reserve(g.cellCount());
		m_noiseSorted.reserve(g.cellCount());
		m_offsetValue.reserve(g.cellCount());
		m_offsetSorted.reserve(g.cellCount());
		m_tailCandidates.reserve(g.cellCount());
		m_held.reserve(g.cellCount());
		m_tailLo.assign(g.cellCount(), -std::numeric_limits<float>::infinity());
		m_tailHi.assign(g.cellCount(), std::numeric_limits<float>::infinity());
		m_tailCount.assign(g.cellCount(), 0);
		m_tailCell.assign(g.cellCount(), 0);
	}
	for (uint32_t c : m_evidenceCells) m_evidence[c] = 0.5f;
	m_evidenceCells.clear();
	for (uint32_t c : m_classCells) m_class[c] = VoxelClass::None;
	m_classCells.clear();
	m_dropVoxels.clear();
	if (!det.ok() || det.planes.empty()) return;
	stats.applied = true;
	if (m_params.model == MethodVariant::Paper)
	{
		computePaper(frame, det, sensor, stats);
		return;
	}

	buildSupport(g, det);
	measureFloorNoise(frame, det, sensor);
	const double maxR2 = m_maxRange * m_maxRange;
	const double res = g.resolution;
	const bool haveSamples = samples && !samples->empty();
	const bool deepTest = m_params.deep_sample_test && haveSamples && m_params.noise_sigmas > 0;
	// Whether the camera's samples share part of their error (see the deep-sample test).
	const bool sharedNoise = m_camera.correlated(1.0, m_fx) > 0;
	// Counting above the plane assumes independent samples: a camera whose
	// noise is time of flight's alone (raised_sample_test). A camera of unknown
	// noise (`custom` with no coefficients: a Kinect v1's 640 x 480 at 62.7
	// deg, structured light) is not taken to have them.
	// (No baseline: no disparity term, so no correlated part either.)
	const bool timeOfFlight = !(m_camera.baseline > 0) && m_camera.independent(1.0, m_fx) > 0;
	const bool raisedTest = deepTest && m_params.raised_sample_test && timeOfFlight;
	const bool smear = smearTest();
	m_tailCandidates.clear();
	m_held.clear();

	// Pass 1: every observed voxel updates its own cell.
	for (uint32_t idx : frame.observedCells())
	{
		const ElevationCell& c = frame.cell(idx);
		const int cx = int(idx % uint32_t(g.nx)), cy = int(idx / uint32_t(g.nx));
		const double x = g.cx(cx), y = g.cy(cy);
		const double dx = x - sensor.x(), dy = y - sensor.y();
		VoxelClass cls;
		double dMean = 0;
		bool deferred = false;  // decided once its samples beyond the band are counted
		if (dx * dx + dy * dy > maxR2)
			cls = VoxelClass::OutOfRange;
		else
		{
			const int block = (cy / m_blockCells) * m_bnx + (cx / m_blockCells);
			const Plane& pl = choosePlane(det, c, x, y, block);
			const double hs = pl.signedDistance(sensor.x(), sensor.y(), sensor.z());
			const double band = groundBand(sensor, hs, x, y, c.mean());
			const double tau = floorOffset(sensor, x, y, c.mean());
			cls = classify(c, x, y, pl, band, dMean, tau);
			if (haveSamples && pl.c > 0 && (cls == VoxelClass::Obstacle || cls == VoxelClass::Drop) &&
				c.count >= minPoints())
			{
				// Judged by its top (bottom) sample while others lie in the band:
				// count the samples beyond the band before it counts.
				const double top = pl.signedDistance(x, y, c.z_max), bottom = pl.signedDistance(x, y, c.z_min);
				if (cls == VoxelClass::Obstacle && top > band && bottom <= band)
				{
					m_tailHi[idx] = float(pl.heightAt(x, y) + band / pl.c);
					m_tailCandidates.push_back({idx, TailKind::Above, 0.f});
					deferred = true;
				}
				else if (cls == VoxelClass::Drop && bottom < -band && top >= -band)
				{
					m_tailLo[idx] = float(pl.heightAt(x, y) - band / pl.c);
					m_tailCandidates.push_back({idx, TailKind::Below, 0.f});
					deferred = true;
				}
			}
			if (deepTest && cls == VoxelClass::Ground && c.count >= minPoints())
			{
				// Floor sample scatter around the plane: one sample's noise and
				// the cells' offsets (d_pth as 3 sigma where not measured).
				const double k = m_params.noise_sigmas, sigma = (band - m_params.d_pth) / k;
				const double t = tau >= 0 ? tau : m_params.d_pth / k;
				const double s = std::sqrt(sigma * sigma + t * t);
				// Where the samples' errors are independent, the binomial tail
				// is exact at any threshold, and one at the smallest hazard's
				// own size counts the most of a hole's wall; a shared error
				// moves whole groups of samples together, so there only the
				// band's 3 sigma (or the step, if larger) is deep enough.
				const double T = sharedNoise ? std::max(m_params.traversable_step, k * s) : m_params.traversable_step;
				if (s > 0 && pl.signedDistance(x, y, c.z_min) < -T && pl.c > 0)
				{
					// signedDistance = c (z - heightAt) for a unit normal.
					m_tailLo[idx] = float(pl.heightAt(x, y) - T / pl.c);
					// A sample's chance to lie below -T: from the plane's noise
					// (s). A camera whose samples share part of their error (a
					// stereo camera's matching window) can put a whole cell low;
					// there it is the larger of that and the chance from the
					// cell's own level dMean with one sample's noise sigma: such
					// a cell has samples below -T for that reason, a hole's cell
					// has them far below its level.
					double p0 = ism::normalTail(T / s);
					if (sharedNoise && sigma > 0) p0 = std::max(p0, ism::normalTail((T + dMean) / sigma));
					m_tailCandidates.push_back({idx, TailKind::Deep, float(p0)});
				}
				else if (
					raisedTest && s > 0 && sigma > 0 && c.count >= minPoints() &&
					pl.signedDistance(x, y, c.z_max) > T && pl.c > 0 &&
					ism::chiSquareAbove(double(c.count) * double(c.variance()) / (sigma * sigma), c.count - 1, k))
				{
					// The same count above the plane, where the cell's samples
					// spread over more than one surface (a low object's face
					// and top, not a ramp's plane).
					m_tailHi[idx] = float(pl.heightAt(x, y) + T / pl.c);
					m_tailCandidates.push_back({idx, TailKind::Raised, float(ism::normalTail(T / s))});
				}
			}
		}
		m_class[idx] = cls;
		m_classCells.push_back(idx);
		switch (cls)
		{
			case VoxelClass::Ground:
				stats.ground++;
				put(idx, float(ism::groundProbability(dMean, m_params)));
				break;
			case VoxelClass::Obstacle:
			case VoxelClass::Drop: {
				if (c.count < minPoints())
				{
					// A lone return (a depth spike) is no evidence of anything.
					stats.sparse++;
					break;
				}
				if (deferred) break;
				const bool drop = cls == VoxelClass::Drop;
				hold(Held{idx, c.count, drop, false}, smear, frame, stats);
				break;
			}
			case VoxelClass::OutOfRange: stats.out_of_range++; break;
			case VoxelClass::None: break;
		}
	}

	// The tail count's list, sized with the samples' buffer on every frame (a
	// later frame then allocates nothing, candidates or not).
	if (samples && m_tailSamples.size() < samples->capacity()) m_tailSamples.resize(samples->capacity());
	if (!m_tailCandidates.empty()) countTailSamples(frame, *samples, stats);
	// range_smear: every class and count of the frame is known now. Judge
	// all held cells first, then give evidence (no verdict reads another).
	for (Held& h : m_held) h.smeared = smeared(frame, h.cell, h.beyond, h.drop, sensor);
	for (const Held& h : m_held)
	{
		if (!h.smeared)
			give(h, frame, stats);
		else
		{
			stats.smeared++;
			if (h.deep) m_class[h.cell] = VoxelClass::Ground;  // it stays the floor it was judged
		}
	}
	m_held.clear();
	clearTailCandidates();

	// Pass 2: the ray to a below-ground voxel crossed the ground plane and went
	// on below it; no floor stopped it in between. Mark those cells, unless
	// this frame saw ground there (a direct observation beats the inference).
	// A ray's part inside the grid is at most its diagonal long: steps of half
	// a cell along it, sized once per grid.
	const double diagonal = std::hypot(double(g.nx), double(g.ny)) * res;
	const size_t maxSteps = size_t(std::ceil(diagonal / (0.5 * res))) + 1;
	if (m_rayCells.size() < maxSteps) m_rayCells.resize(maxSteps);
	for (uint32_t idx : m_dropVoxels)
	{
		const ElevationCell& c = frame.cell(idx);
		const int cx = int(idx % uint32_t(g.nx)), cy = int(idx / uint32_t(g.nx));
		const double x = g.cx(cx), y = g.cy(cy);
		const int block = (cy / m_blockCells) * m_bnx + (cx / m_blockCells);
		const Plane& pl = choosePlane(det, c, x, y, block);
		const double hs = pl.signedDistance(sensor.x(), sensor.y(), sensor.z());
		// The deepest sample's ray crossed the ground nearest to the robot:
		// it bounds the part of the hole that no floor stopped.
		const double dp = pl.signedDistance(x, y, c.z_min);
		if (!(hs > 0) || !(dp < 0)) continue;
		const double t = hs / (hs - dp);  // ray parameter at the crossing
		const double ex = sensor.x() + t * (x - sensor.x()), ey = sensor.y() + t * (y - sensor.y());
		double lx = x - ex, ly = y - ey;
		double len = std::sqrt(lx * lx + ly * ly);
		// The ray got to the crossing only if nothing stood in its way. The
		// sample (its cell's centre and z_min) may put the crossing in the
		// shadow of a box, which no ray reached: then the cells would be
		// painted where no sensor looked.
		if (rayBlocked(frame, pl, sensor, hs, ex, ey))
		{
			stats.drop_rays_unsupported++;
			continue;
		}
		if (len > diagonal)
		{
			// The voxel is in the grid: farther from it than the grid's
			// diagonal, the ray is outside it (a sensor outside the grid).
			const double s = diagonal / len;
			lx *= s;
			ly *= s;
			len = diagonal;
		}
		const float p = m_evidence[idx];
		const int steps = int(std::ceil(len / (0.5 * res)));
		// March in cell units from the voxel back along the ray (no division by the
		// resolution per step; the step's fraction s / steps is one division).
		const double vx = (x - g.x_min) / res, vy = (y - g.y_min) / res;
		const double sx = lx / res, sy = ly / res;
		// The cells of the steps first, in a loop without branches (it
		// vectorizes; -1 outside the grid), then the evidence.
		int32_t* __restrict cellAt = m_rayCells.data();
		const double nxd = g.nx, nyd = g.ny;
		const int32_t nx = g.nx;
		for (int s = 1; s < steps; s++)
		{
			const double back = 1.0 - double(s) / steps;
			const double fx = vx - sx * back, fy = vy - sy * back;
			const bool in = (fx >= 0) & (fy >= 0) & (fx < nxd) & (fy < nyd);
			const int32_t qx = int32_t(in ? fx : 0.0), qy = int32_t(in ? fy : 0.0);
			cellAt[s] = in ? qy * nx + qx : -1;
		}
		int lastCell = -1;
		for (int s = 1; s < steps; s++)
		{
			const int q = cellAt[s];
			if (q < 0 || q == lastCell || uint32_t(q) == idx) continue;
			lastCell = q;
			const VoxelClass qc = m_class[size_t(q)];
			if (qc == VoxelClass::Ground) continue;
			if (m_evidence[size_t(q)] <= 0.5f) stats.drop_ray_cells++;
			put(uint32_t(q), p);
		}
	}
}

namespace
{
/** GridGeometry::ix()'s floor((x - x_min) / res) from q = (x - x_min) * invRes
 * (invRes = 1 / res), without its division and its call to floor() (a
 * library call without SSE4.1): the product differs from the quotient by at
 * most 3.4e-16 of it, under 1e-9 for a quotient below 1e6, so where q is in
 * [0, 1e6) and more than 1e-9 from an integer, its truncation i is the
 * quotient's floor. False elsewhere (a negative index, a NaN, near a cell's
 * border): ix() decides there. */
inline bool fastCellIndex(double q, int& i)
{
	const bool inRange = q >= 0 && q < 1e6;  // false for a NaN
	i = int(inRange ? q : 0.0);
	const double frac = q - double(i);
	return inRange & (frac > 1e-9) & (frac < 1.0 - 1e-9);
}
}  // namespace

void InverseSensorModel::computePaper(
	const ElevationGrid& frame, const GroundDetection& det, const Eigen::Vector3d& sensor, IsmStats& stats)
{
	// The paper's ray model: every voxel c_v of the 2.5D map gives evidence to
	// the 2D cells on its ray from the sensor, eq. (5) up to |c_v| and none
	// behind it (eq. (6), our reading). One plane (the RANSAC ground), the fixed
	// band d_pth, eq. (4) for the density; several voxels on one cell in one
	// frame combine as in the default model (the largest occupied evidence,
	// else the strongest free one), one update per cell and frame.
	const GridGeometry& g = frame.geometry();
	const Plane& pl = det.planes.front();
	const double res = g.resolution;
	const double maxR2 = m_maxRange * m_maxRange;
	const double sx = sensor.x(), sy = sensor.y();
	const paper::RayFan fan(res, m_maxRange);
	const float floorP = ism::kEvidenceFloor;
	const bool groundAtLeastFloor = float(m_params.K_g) >= floorP;
	const double invRes = 1.0 / res;

	// 1. Classify every voxel in range (ground: both ends within d_pth); its
	// own cell gets eq. (5) at |c| = |c_v|.
	m_paperVoxels.clear();
	const float groundOwn = float(paper::groundRay(0, 0, m_params));
	for (uint32_t idx : frame.observedCells())
	{
		const ElevationCell& c = frame.cell(idx);
		const int cx = int(idx % uint32_t(g.nx)), cy = int(idx / uint32_t(g.nx));
		const double x = g.cx(cx), y = g.cy(cy);
		const double dx = x - sx, dy = y - sy;
		const double r2 = dx * dx + dy * dy;
		m_classCells.push_back(idx);
		if (r2 > maxR2)
		{
			m_class[idx] = VoxelClass::OutOfRange;
			stats.out_of_range++;
			continue;
		}
		const double dTop = pl.signedDistance(x, y, c.z_max), dBot = pl.signedDistance(x, y, c.z_min);
		const bool ground = std::abs(dTop) <= m_params.d_pth && std::abs(dBot) <= m_params.d_pth;
		// The paper has ground and obstacle only; a voxel below the plane is
		// an obstacle voxel (its class says Drop for the viewer and the stats).
		const VoxelClass cls =
			ground ? VoxelClass::Ground : (dTop < -m_params.d_pth ? VoxelClass::Drop : VoxelClass::Obstacle);
		m_class[idx] = cls;
		(cls == VoxelClass::Ground ? stats.ground : cls == VoxelClass::Drop ? stats.drop : stats.obstacle)++;
		const float peak =
			ground ? 0.f : float(std::max(0.5, paper::densityConfidence(c.count, c.span(), m_params, res)));
		put(idx, ground ? groundOwn : peak);
		const double dist = std::sqrt(r2);
		const int last = fan.lastSample(dist);
		if (last >= 0) m_paperVoxels.push_back({idx, fan.binOf(dx, dy), last, float(dist), peak});
	}

	// 2. Sort by bin, and within a bin farthest first: two stable counting
	// sorts (last sample descending, then bin), O(voxels + bins + samples).
	const size_t n = m_paperVoxels.size();
	m_paperSorted.resize(n);
	const int samples = fan.lastSample(m_maxRange) + 1;
	m_paperCount.assign(size_t(std::max(samples, fan.bins)) + 1, 0);
	for (const PaperVoxel& v : m_paperVoxels) m_paperCount[size_t(samples - 1 - v.last) + 1]++;
	for (size_t i = 1; i < m_paperCount.size(); i++) m_paperCount[i] += m_paperCount[i - 1];
	for (const PaperVoxel& v : m_paperVoxels) m_paperSorted[m_paperCount[size_t(samples - 1 - v.last)]++] = v;
	std::fill(m_paperCount.begin(), m_paperCount.end(), 0);
	for (const PaperVoxel& v : m_paperSorted) m_paperCount[size_t(v.bin) + 1]++;
	for (size_t i = 1; i < m_paperCount.size(); i++) m_paperCount[i] += m_paperCount[i - 1];
	for (const PaperVoxel& v : m_paperSorted) m_paperVoxels[m_paperCount[size_t(v.bin)]++] = v;

	// A ground voxel's evidence at sample k, K_g + (0.5 - K_g) / (1 + e^(|c_v| - r_k)),
	// with e^(|c_v| - r_k) as e^|c_v| e^-r_k: one exp per change of the bin's farthest
	// ground voxel instead of one per sample (the two forms differ by a few units in
	// the last place of a double; what the map gets is a float). Up to e^300.
	const bool factorGround = m_maxRange <= 300;
	m_paperExpNegR.resize(size_t(std::max(samples, 0)));
	for (int k = 0; k < samples; k++) m_paperExpNegR[size_t(k)] = std::exp(-fan.radius(k));
	const double Kg = m_params.K_g, groundSpan = 0.5 - m_params.K_g;
	// The cells that leave 0.5 in the sweep, in that order, appended to
	// m_evidenceCells after it: a cell is listed at most once, so the grid's
	// cell count bounds them (one more: each sample writes its cell at the
	// list's end, which moves on only for a new one).
	m_paperNewCells.resize(g.cellCount() + 1);
	uint32_t* const newCells = m_paperNewCells.data();
	size_t listed = 0;
	// 3. Sweep each bin's ray from its farthest voxel to the sensor. At a
	// sample, the ground voxels beyond it give K_g + (0.5 - K_g) / (1 + e^delta)
	// (delta = |c_v| - r_k), strongest for the farthest one; each obstacle voxel
	// beyond it gives max(P_rho, 0.5) exp(-delta^2 / 2 sigma^2), which falls to
	// the floor within a few decimetres and stays there.
	for (size_t i = 0; i < n;)
	{
		const int bin = m_paperVoxels[i].bin;
		const double ux = std::cos(fan.angle(bin)), uy = std::sin(fan.angle(bin));
		double farGround = -1;    // |c_v| of the farthest ground voxel reached so far
		double expFarGround = 0;  // e^farGround (factorGround)
		bool saturated = false;   // an obstacle's evidence has fallen to the floor
		m_paperActive.clear();
		int lastCell = -1;
		float lastP = 0.5f;
		// The bin's first voxel reaches the most samples: when k reaches 0,
		// every voxel of the bin has been taken in.
		for (int k = m_paperVoxels[i].last; k >= 0; k--)
		{
			for (; i < n && m_paperVoxels[i].bin == bin && m_paperVoxels[i].last >= k; i++)
			{
				const PaperVoxel& v = m_paperVoxels[i];
				if (v.peak != 0.f)
					m_paperActive.push_back(v);
				else if (double(v.dist) > farGround)
				{
					farGround = double(v.dist);
					if (factorGround) expFarGround = std::exp(farGround);
				}
			}
			const double r = fan.radius(k);
			float occ = 0.5f, fr = saturated ? floorP : 0.5f;
			// Ground evidence is at least K_g: once saturated at the floor, it
			// cannot lower fr (most of a bin's samples, in front of a wall).
			if (farGround >= r && !(saturated && groundAtLeastFloor))
				fr = std::min(
					fr, factorGround ? float(Kg + groundSpan / (1.0 + expFarGround * m_paperExpNegR[size_t(k)]))
									 : float(paper::groundRay(r, farGround, m_params)));
			for (size_t j = 0; j < m_paperActive.size();)
			{
				const float p =
					float(paper::obstacleRay(r, double(m_paperActive[j].dist), m_paperActive[j].peak, m_params));
				if (p > 0.5f)
				{
					occ = std::max(occ, p);
					j++;
					continue;
				}
				// Free from here to the sensor, and falling: once one obstacle's
				// evidence reaches the floor, no free evidence can beat it.
				if (p <= floorP) saturated = true;
				if (saturated)
				{
					fr = floorP;
					m_paperActive[j] = m_paperActive.back();
					m_paperActive.pop_back();
					continue;
				}
				fr = std::min(fr, p);
				j++;
			}
			const float p = occ > 0.5f ? occ : fr;
			if (p == 0.5f) continue;
			// The sample's cell: g.ix(), g.iy(), without their divisions where
			// that gives the same cells.
			const double x = sx + r * ux, y = sy + r * uy;
			int qx, qy;
			if (!(fastCellIndex((x - g.x_min) * invRes, qx) & fastCellIndex((y - g.y_min) * invRes, qy)))
			{
				qx = g.ix(x);
				qy = g.iy(y);
			}
			if (!g.inside(qx, qy)) continue;
			const int q = int(g.index(qx, qy));
			if (q == lastCell && p == lastP) continue;
			lastCell = q;
			lastP = p;
			// put(), with the cell listed without a branch: whether a ray's
			// cell was already given evidence by another bin is a coin toss
			// near the sensor.
			newCells[listed] = uint32_t(q);
			listed += size_t(combineEvidence(uint32_t(q), p));
		}
	}
	m_evidenceCells.insert(m_evidenceCells.end(), newCells, newCells + listed);
}

}  // namespace gam
