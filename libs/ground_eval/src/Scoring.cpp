// Ground-aware mapping for MRPT -- map evaluation: scoring a map against the ground
// truth (see Scoring.h for the rules).
#include "gam/eval/Scoring.h"

#include <algorithm>
#include <cmath>

#include "PathNames.h"

namespace gam::eval
{
Resampled resample(const GroundTruth& gt, const RosMap& map)
{
	Resampled r;
	const size_t n = gt.label.size();
	r.pMax.assign(n, 0.5f);
	r.pMin.assign(n, 0.5f);
	const double R = map.resolution, h = 0.5 * gt.resolution;
	// map cell i has its centre at origin + (i + 0.5) R; the cells whose centres are in
	// [a, b) are ceil((a - o)/R - 0.5) .. ceil((b - o)/R - 0.5) - 1.
	auto range = [&](double a, double b, double o, int& i0, int& i1) {
		const double eps = 1e-9;
		i0 = int(std::ceil((a - o) / R - 0.5 - eps));
		i1 = int(std::ceil((b - o) / R - 0.5 - eps)) - 1;
	};
	for (size_t i = 0; i < n; i++)
	{
		const double cx = gt.x[i], cy = gt.y[i];
		int c0, c1, r0, r1;
		range(cx - h, cx + h, map.origin_x, c0, c1);
		range(cy - h, cy + h, map.origin_y, r0, r1);
		float mx = -1, mn = 2;
		bool any = false;
		if (c0 <= c1 && r0 <= r1)
		{
			for (int row = r0; row <= r1; row++)
				for (int col = c0; col <= c1; col++)
				{
					if (!map.inside(col, row)) continue;
					const float p = float(map.pOcc(col, row));
					mx = std::max(mx, p);
					mn = std::min(mn, p);
					any = true;
				}
		}
		else
		{
			const int col = int(std::floor((cx - map.origin_x) / R)), row = int(std::floor((cy - map.origin_y) / R));
			if (map.inside(col, row))
			{
				mx = mn = float(map.pOcc(col, row));
				any = true;
			}
		}
		if (any)
		{
			r.pMax[i] = mx;
			r.pMin[i] = mn;
		}
	}
	return r;
}

std::vector<CellState> classify(const Resampled& r, double occ, double fr)
{
	std::vector<CellState> s(r.pMax.size(), CellState::Unknown);
	for (size_t i = 0; i < s.size(); i++)
	{
		if (r.pMax[i] > occ)
			s[i] = CellState::Occupied;
		else if (r.pMin[i] < fr)
			s[i] = CellState::Free;
	}
	return s;
}

namespace
{
/** Adds a cell in state `s` to the occupied / free / unknown counts of `c`. */
template <class Counts>
void tally(Counts& c, CellState s)
{
	if (s == CellState::Occupied)
		c.occupied++;
	else if (s == CellState::Free)
		c.free++;
	else
		c.unknown++;
}

void count(CellCounts& c, CellState s)
{
	c.n++;
	tally(c, s);
}

bool isObstacle(Label l) { return l == Label::Obstacle || l == Label::Drop; }

// The cells the floor's tolerance band is measured from: every GT obstacle or
// drop cell, observed or not. A cell of an obstacle, hole or overhang that no
// noise-free ray reached is still there: a wall whose face lies in the outer
// sixth of the floor cell in front of it (beyond that cell's outermost probe)
// leaves that cell free and takes every ray's end, so the wall's own cells
// stay unobserved, and the floor cell that holds its face was scored as
// floor. The GT file gives an unobserved cell's object but not its label: a
// cell of an object that is not a ramp is one of its obstacle or drop cells
// (the simulator gives a free cell no object but a ramp's); a ramp's
// unobserved cells may be either and are left out.
std::vector<uint8_t> objectCells(const GroundTruth& gt)
{
	std::vector<uint8_t> solid(gt.label.size(), 0);
	for (size_t i = 0; i < solid.size(); i++)
	{
		if (isObstacle(gt.label[i]))
			solid[i] = 1;
		else if (gt.label[i] == Label::Unobserved && gt.objectId[i] != 0)
		{
			const GtObject* o = gt.object(gt.objectId[i]);
			solid[i] = o && o->category != "ramp";
		}
	}
	return solid;
}

Reading score(
	const GroundTruth& gt, const std::vector<CellState>& st, const std::vector<uint8_t>& floorMask, const Options& opt)
{
	Reading rd;
	std::map<int, ObjectScore> objs;
	std::map<int, CellCounts> ramps;
	for (size_t i = 0; i < st.size(); i++)
	{
		const Label l = gt.label[i];
		if (l == Label::Unobserved) continue;
		if (isObstacle(l))
		{
			count(rd.obstacle, st[i]);
			const int id = gt.objectId[i];
			if (id == 0) continue;  // (the simulator gives every obstacle cell an object)
			auto& o = objs[id];
			o.observed++;
			tally(o, st[i]);
		}
		else if (floorMask[i])
		{
			count(rd.floor, st[i]);
			const GtObject* o = gt.objectId[i] ? gt.object(gt.objectId[i]) : nullptr;
			if (o && o->category == "ramp")
			{
				count(rd.ramp, st[i]);
				count(ramps[gt.objectId[i]], st[i]);
			}
		}
	}
	for (const auto& [id, c] : ramps) rd.ramps.push_back({id, gt.object(id)->name, c});
	for (auto& [id, o] : objs)
	{
		const GtObject* g = gt.object(id);
		o.id = id;
		o.name = g ? g->name : "";
		o.category = g ? g->category : "none";
		o.detected = o.occupied >= std::max(1, opt.min_hits);
		auto& c = rd.categories[o.category];
		c.objects++;
		c.detected += o.detected ? 1 : 0;
		c.coverageSum += o.coverage();
		rd.objects.push_back(o);
	}
	return rd;
}
}  // namespace

MapScore evaluate(const GroundTruth& gt, const RosMap& map, const Options& opt)
{
	MapScore ms;
	ms.name = detail::baseNoExt(map.yamlPath);
	ms.yamlPath = map.yamlPath;
	// floor mask: observed free cells farther than tolerance_cells from obstacle/drop cells
	const int t = std::max(0, opt.tolerance_cells);
	const std::vector<uint8_t> solid = objectCells(gt);
	std::vector<uint8_t> floorMask(gt.label.size(), 0);
	for (int iy = 0; iy < gt.ny; iy++)
		for (int ix = 0; ix < gt.nx; ix++)
		{
			const size_t i = gt.idx(ix, iy);
			if (gt.label[i] != Label::Free) continue;
			bool near = false;
			for (int dy = -t; dy <= t && !near; dy++)
				for (int dx = -t; dx <= t && !near; dx++)
				{
					const int x = ix + dx, y = iy + dy;
					if (x < 0 || y < 0 || x >= gt.nx || y >= gt.ny) continue;
					near = solid[gt.idx(x, y)] != 0;
				}
			if (near)
				ms.excluded_floor++;
			else
				floorMask[i] = 1;
		}
	const Resampled r = resample(gt, map);
	const double u = opt.unknown_tolerance;
	ms.main = score(gt, classify(r, 0.5 + u, 0.5 - u), floorMask, opt);
	ms.main.name = "p>0.5";
	ms.main.occ = 0.5 + u;
	ms.main.free = 0.5 - u;
	ms.strict = score(gt, classify(r, map.occupied_thresh, map.free_thresh), floorMask, opt);
	ms.strict.name = "map_server";
	ms.strict.occ = map.occupied_thresh;
	ms.strict.free = map.free_thresh;
	return ms;
}

}  // namespace gam::eval
