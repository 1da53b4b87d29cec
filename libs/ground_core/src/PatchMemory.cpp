// Ground-aware mapping for MRPT -- the ramp patches of a camera's earlier frames.
#include "gam/core/PatchMemory.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gam
{
PatchMemory::PatchMemory()
{
	// Room for the most the memory ever holds: no allocation per frame.
	m_patches.reserve(kMaxPlanes);
	m_next.reserve(kMaxPlanes);
	m_savedPatches.reserve(kMaxPlanes);
	m_nodes.reserve(kMaxPlanes * kMaxNodesPerPatch);
	m_nextNodes.reserve(kMaxPlanes * kMaxNodesPerPatch);
	m_savedNodes.reserve(kMaxPlanes * kMaxNodesPerPatch);
	m_keep.reserve(kMaxPlanes);
	m_frames.reserve(kMaxPlanes);
	m_augmented.planes.reserve(kMaxPlanes);
	m_augmented.plane_support.reserve(kMaxPlanes);
	m_augmented.nodes.reserve(kMaxPlanes * kMaxNodesPerPatch);
}

void PatchMemory::save()
{
	m_savedPatches = m_patches;
	m_savedNodes = m_nodes;
	m_savedPath = m_path;
}

void PatchMemory::restore()
{
	m_patches = m_savedPatches;
	m_nodes = m_savedNodes;
	m_path = m_savedPath;
}

void PatchMemory::clear()
{
	m_patches.clear();
	m_nodes.clear();
	m_savedPatches.clear();
	m_savedNodes.clear();
	m_path = m_savedPath = Path{};
	m_applied = 0;
}

double PatchMemory::advance(const Eigen::Vector2d& robot)
{
	if (m_path.started) m_path.travelled += (robot - m_path.last).norm();
	m_path.last = robot;
	m_path.started = true;
	return m_path.travelled;
}

size_t PatchMemory::repeatedBy(const Patch& p, const GroundDetection& det, double band, double reach) const
{
	const double reach2 = reach * reach;
	for (size_t k = 1; k < det.planes.size(); k++)
	{
		const Plane& q = det.planes[k];
		bool near = false, same = true;
		for (uint32_t i = p.begin; i < p.end && same; i++)
		{
			const Eigen::Vector2f& n = m_nodes[i];
			same = std::abs(q.heightAt(n.x(), n.y()) - p.plane.heightAt(n.x(), n.y())) <= band;
		}
		if (!same) continue;
		for (const GroundNode& g : det.nodes)
		{
			if (g.plane_id != int(k)) continue;
			for (uint32_t i = p.begin; i < p.end && !near; i++)
			{
				const double dx = double(g.x) - m_nodes[i].x(), dy = double(g.y) - m_nodes[i].y();
				near = dx * dx + dy * dy <= reach2;
			}
			if (near) return k;
		}
	}
	return 0;
}

bool PatchMemory::sloped(const GroundDetection& det, size_t k, double rise)
{
	// How much the plane rises across its own nodes, along its gradient.
	const Plane& pl = det.planes[k];
	if (!(std::abs(pl.c) > 1e-9)) return false;
	const double gx = -pl.a / pl.c, gy = -pl.b / pl.c, g = std::hypot(gx, gy);
	if (!(g > 0)) return false;
	double lo = std::numeric_limits<double>::infinity(), hi = -lo;
	for (const GroundNode& n : det.nodes)
		if (n.plane_id == int(k))
		{
			const double along = (gx * n.x + gy * n.y) / g;
			lo = std::min(lo, along);
			hi = std::max(hi, along);
		}
	return hi > lo && g * (hi - lo) > rise;
}

const GroundDetection& PatchMemory::apply(
	const GroundDetection& det, double travelled, double forgetAfter, double band, double reach, double rise)
{
	m_applied = 0;
	if (!(forgetAfter > 0) || !det.ok() || det.planes.empty())
	{
		// Nothing to judge against, or no memory: the frame as it is. (A frame
		// without a ground plane forgets nothing either.)
		if (!(forgetAfter > 0)) clear();
		return det;
	}
	// The remembered patches this frame keeps: seen within forgetAfter of
	// travel and not repeated by a patch of its own (which supersedes them).
	// A patch of this frame that repeats a remembered one counts its frames.
	m_keep.assign(m_patches.size(), 0);
	m_frames.assign(det.planes.size(), 1);
	size_t kept = 0;
	for (size_t i = 0; i < m_patches.size(); i++)
	{
		if (travelled - m_patches[i].seen_at > forgetAfter) continue;
		if (const size_t k = repeatedBy(m_patches[i], det, band, reach))
			m_frames[k] = std::max(m_frames[k], m_patches[i].frames + 1);
		else
		{
			m_keep[i] = 1;
			if (m_patches[i].frames >= kMinFrames) kept++;
		}
	}
	const size_t room = kMaxPlanes > det.planes.size() ? kMaxPlanes - det.planes.size() : 0;

	// The next memory: this frame's patches, then the kept ones (the most
	// recently seen first), at most kMaxPlanes - 1 patches.
	m_next.clear();
	m_nextNodes.clear();
	auto remember = [&](const Plane& plane, double seenAt, int frames, auto&& forEachNode) {
		if (m_next.size() + 1 >= kMaxPlanes) return;
		Patch p;
		p.plane = plane;
		p.seen_at = seenAt;
		p.frames = frames;
		p.begin = uint32_t(m_nextNodes.size());
		forEachNode([&](float x, float y) {
			if (m_nextNodes.size() - p.begin < kMaxNodesPerPatch) m_nextNodes.emplace_back(x, y);
		});
		p.end = uint32_t(m_nextNodes.size());
		if (p.end > p.begin) m_next.push_back(p);
	};
	for (size_t k = 1; k < det.planes.size(); k++)
		if (sloped(det, k, rise))
			remember(det.planes[k], travelled, m_frames[k], [&](auto&& add) {
				for (const GroundNode& g : det.nodes)
					if (g.plane_id == int(k)) add(g.x, g.y);
			});

	// The ISM's detection: this frame's planes and patch nodes, then the kept
	// patches that fit in the support bits.
	const GroundDetection* out = &det;
	if (kept && room)
	{
		m_augmented.clear();
		m_augmented.status = det.status;
		m_augmented.planes = det.planes;
		m_augmented.plane_support = det.plane_support;
		m_augmented.patch_inlier_distance = det.patch_inlier_distance;
		m_augmented.ground_from_mount = det.ground_from_mount;
		m_augmented.tree_plane = det.tree_plane;
		for (const GroundNode& g : det.nodes)
			if (g.plane_id >= 1) m_augmented.nodes.push_back(g);
	}
	// Most recently seen first.
	for (size_t pass = 0; pass < m_patches.size(); pass++)
	{
		size_t best = m_patches.size();
		for (size_t i = 0; i < m_patches.size(); i++)
			if (m_keep[i] && (best == m_patches.size() || m_patches[i].seen_at > m_patches[best].seen_at)) best = i;
		if (best == m_patches.size()) break;
		m_keep[best] = 0;
		const Patch& p = m_patches[best];
		if (room && m_applied < room && p.frames >= kMinFrames)
		{
			if (!m_applied) m_augmented.remembered_from = m_augmented.planes.size();
			const int id = int(m_augmented.planes.size());
			m_augmented.planes.push_back(p.plane);
			m_augmented.plane_support.push_back(p.end - p.begin);
			for (uint32_t i = p.begin; i < p.end; i++)
			{
				GroundNode g;
				g.x = m_nodes[i].x();
				g.y = m_nodes[i].y();
				g.z = float(p.plane.heightAt(g.x, g.y));
				g.plane_id = id;
				m_augmented.nodes.push_back(g);
			}
			m_applied++;
			out = &m_augmented;
		}
		remember(p.plane, p.seen_at, p.frames, [&](auto&& add) {
			for (uint32_t i = p.begin; i < p.end; i++) add(m_nodes[i].x(), m_nodes[i].y());
		});
	}
	m_patches.swap(m_next);
	m_nodes.swap(m_nextNodes);
	return *out;
}

}  // namespace gam
