// Ground-aware mapping for MRPT
#include "gam/core/SensorMount.h"

#include <Eigen/Eigenvalues>
#include <random>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace gam
{
SensorPlane planeInSensorFrame(const Plane& world, const Eigen::Isometry3d& worldFromSensor)
{
	// p_w = R p_s + t, so n_w . p_w + d_w = (R^T n_w) . p_s + (n_w . t + d_w).
	const Eigen::Vector3d nw = world.normal();
	const double len = nw.norm();
	SensorPlane s;
	s.normal = worldFromSensor.linear().transpose() * (nw / len);
	s.d = (nw.dot(worldFromSensor.translation()) + world.d) / len;
	return s;
}

std::optional<SensorMount> mountFromFloor(const SensorPlane& floorInSensor)
{
	Eigen::Vector3d n = floorInSensor.normal;
	double d = floorInSensor.d;
	const double len = n.norm();
	if (!std::isfinite(len) || !std::isfinite(d) || len < 1e-12) return std::nullopt;
	n /= len;
	d /= len;
	if (d < 0)  // orient the normal toward the sensor: the sensor is above the floor
	{
		n = -n;
		d = -d;
	}
	if (!(d > 0)) return std::nullopt;
	SensorMount m;
	m.height = d;
	m.pitch = std::asin(std::clamp(-n.x(), -1.0, 1.0));
	m.roll = std::atan2(n.y(), n.z());
	return m;
}
namespace
{
double medianOf(std::vector<double> v)
{
	std::sort(v.begin(), v.end());
	const size_t n = v.size();
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
}  // namespace

MountEstimate estimateMount(const std::vector<SensorMount>& frames)
{
	MountEstimate e;
	if (frames.empty()) return e;
	const double deg = M_PI / 180.0;
	const std::pair<double SensorMount::*, double> fields[] = {
		{&SensorMount::height, 0.005}, {&SensorMount::pitch, 0.1 * deg}, {&SensorMount::roll, 0.1 * deg}};
	double med[3], lim[3];
	for (int k = 0; k < 3; k++)
	{
		std::vector<double> c;
		for (const SensorMount& m : frames) c.push_back(m.*fields[k].first);
		med[k] = medianOf(c);
		for (double& x : c) x = std::abs(x - med[k]);
		lim[k] = std::max(3.0 * 1.4826 * medianOf(c), fields[k].second);
	}
	double sum[3] = {0, 0, 0}, sq[3] = {0, 0, 0};
	for (const SensorMount& m : frames)
	{
		bool keep = true;
		for (int k = 0; k < 3; k++) keep = keep && std::abs(m.*fields[k].first - med[k]) <= lim[k];
		if (!keep) continue;
		e.used++;
		for (int k = 0; k < 3; k++)
		{
			sum[k] += m.*fields[k].first;
			sq[k] += (m.*fields[k].first) * (m.*fields[k].first);
		}
	}
	const double n = double(e.used);
	for (int k = 0; k < 3; k++)
	{
		const double mean = sum[k] / n;
		const double var = e.used > 1 ? std::max(0.0, (sq[k] - n * mean * mean) / (n - 1)) : 0.0;
		e.mean.*fields[k].first = mean;
		e.standard_error.*fields[k].first = std::sqrt(var / n);
	}
	return e;
}

void MountMonitor::setParams(const MountCheckParams& p)
{
	if (!(p.tolerance_z > 0) || !(p.tolerance_deg > 0) || p.alarm_frames < 1 || p.window < 1)
		throw std::invalid_argument("mount check: tolerances must be > 0, alarm_frames and window >= 1");
	m_params = p;
	reset();
}

void MountMonitor::reset()
{
	m_status = MountStatus{};
	m_ring.clear();
	m_ring.reserve(size_t(m_params.window));
	m_scratch.reserve(size_t(m_params.window));
	m_next = 0;
}

void MountMonitor::update(const SensorMount& declared, const std::optional<SensorMount>& measured)
{
	if (!m_params.enabled || !measured) return;
	MountStatus& s = m_status;
	s.frames_checked++;
	s.declared = declared;
	s.last = *measured;
	s.has_last = true;
	const double tol = m_params.tolerance_deg * M_PI / 180.0;
	const bool disagrees = std::abs(measured->height - declared.height) > m_params.tolerance_z ||
						   std::abs(measured->pitch - declared.pitch) > tol ||
						   std::abs(measured->roll - declared.roll) > tol;
	if (disagrees)
	{
		s.frames_disagreeing++;
		s.disagreeing_in_a_row++;
		s.agreeing_in_a_row = 0;
		if (!s.alarm && s.disagreeing_in_a_row >= m_params.alarm_frames)
		{
			s.alarm = true;
			s.alarms_raised++;
		}
	}
	else
	{
		s.agreeing_in_a_row++;
		s.disagreeing_in_a_row = 0;
		if (s.alarm && s.agreeing_in_a_row >= m_params.alarm_frames) s.alarm = false;
	}

	// Running estimate: the median of each value over the last `window` frames
	// (a frame on a ramp or with a bad plane moves it by one rank, not by its size).
	if (m_ring.size() < size_t(m_params.window))
		m_ring.push_back(*measured);
	else
		m_ring[m_next] = *measured;
	m_next = (m_next + 1) % size_t(m_params.window);
	auto median = [&](double SensorMount::*field) {
		m_scratch.clear();
		for (const SensorMount& m : m_ring) m_scratch.push_back(m.*field);
		auto mid = m_scratch.begin() + std::ptrdiff_t(m_scratch.size() / 2);
		std::nth_element(m_scratch.begin(), mid, m_scratch.end());
		return *mid;
	};
	s.estimate = {median(&SensorMount::height), median(&SensorMount::pitch), median(&SensorMount::roll)};
	s.has_estimate = m_ring.size() >= size_t(m_params.alarm_frames);
}
std::optional<SensorPlane> searchFloor(
	const std::vector<Eigen::Vector3d>& pts, const SensorMount& guess, const FloorSearchParams& p, unsigned seed,
	size_t* inliersOut)
{
	if (inliersOut) *inliersOut = 0;
	const size_t n = pts.size();
	if (n < 3 || n < p.min_inliers) return std::nullopt;
	std::mt19937 rng(seed);
	std::uniform_int_distribution<size_t> pick(0, n - 1);
	auto angleDiff = [](double a, double b) { return std::abs(std::remainder(a - b, 2 * M_PI)); };
	auto accepted = [&](const SensorPlane& pl, SensorMount& m) {
		const auto mm = mountFromFloor(pl);
		if (!mm) return false;
		m = *mm;
		return std::abs(m.height - guess.height) <= p.height_tolerance &&
			   angleDiff(m.pitch, guess.pitch) <= p.pitch_tolerance &&
			   angleDiff(m.roll, guess.roll) <= p.roll_tolerance;
	};
	double scale = 1;  // of the inlier band: the refits narrow it
	auto isInlier = [&](const SensorPlane& pl, const Eigen::Vector3d& q) {
		return std::abs(pl.normal.dot(q) + pl.d) <= scale * (p.inlier_distance + p.inlier_distance_per_m * q.norm());
	};
	SensorPlane best{};
	size_t bestCount = 0;
	for (int it = 0; it < p.iterations; it++)
	{
		const Eigen::Vector3d& a = pts[pick(rng)];
		const Eigen::Vector3d& b = pts[pick(rng)];
		const Eigen::Vector3d& c = pts[pick(rng)];
		Eigen::Vector3d nrm = (b - a).cross(c - a);
		const double len = nrm.norm();
		if (!(len > 1e-9)) continue;
		SensorPlane pl{nrm / len, 0};
		pl.d = -pl.normal.dot(a);
		SensorMount m;
		if (!accepted(pl, m)) continue;
		size_t count = 0;
		for (const auto& q : pts) count += isInlier(pl, q);
		if (count > bestCount)
		{
			bestCount = count;
			best = pl;
		}
	}
	if (bestCount < std::max<size_t>(3, p.min_inliers)) return std::nullopt;
	// Refit to the inliers (total least squares) in a band halved each round:
	// the refitted plane's inliers are the floor's, not the 3 points', and the
	// foot of a wall or the edge of a mat no longer pulls it. A plane through
	// a floor/wall corner (many points near both, on neither) loses its
	// inliers here and is no floor.
	for (int round = 0; round < 3; round++)
	{
		scale = round == 0 ? 1.0 : 0.5 * scale;
		Eigen::Vector3d mean = Eigen::Vector3d::Zero();
		size_t k = 0;
		for (const auto& q : pts)
			if (isInlier(best, q))
			{
				mean += q;
				k++;
			}
		if (k < std::max<size_t>(3, p.min_inliers)) return std::nullopt;
		mean /= double(k);
		Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
		for (const auto& q : pts)
			if (isInlier(best, q)) cov += (q - mean) * (q - mean).transpose();
		Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
		Eigen::Vector3d nrm = es.eigenvectors().col(0);
		if (nrm.dot(best.normal) < 0) nrm = -nrm;
		SensorPlane refit{nrm, -nrm.dot(mean)};
		SensorMount m;
		if (!accepted(refit, m)) return std::nullopt;
		best = refit;
		bestCount = k;
	}
	if (inliersOut) *inliersOut = bestCount;
	return best;
}

}  // namespace gam
