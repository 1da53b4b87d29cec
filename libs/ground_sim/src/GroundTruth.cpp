// Ground-aware mapping for MRPT -- scene simulator: ground-truth 2D grid.
#include "gam/sim/GroundTruth.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gam::sim
{
int GridSpec::nx() const { return std::max(1, int(std::lround((max_x - min_x) / resolution))); }
int GridSpec::ny() const { return std::max(1, int(std::lround((max_y - min_y) / resolution))); }

Label GroundTruthGrid::probe(const Scene& scene, const GridSpec& s, double x, double y, int& obj, double* support)
{
	obj = 0;
	if (!scene.has_floor) return Label::Drop;
	double g = 0;
	int negObj = 0, supportObj = 0;
	for (const auto& h : scene.holes)
		if (h.containsXY(x, y) && -h.depth < g)
		{
			g = -h.depth;
			negObj = h.object_id;
		}
	struct Ext
	{
		double lo, hi;
		int id;
		bool trav;
	};
	std::vector<Ext> ext;
	for (const auto& sol : scene.solids)
	{
		if (x < sol.bbox.min().x() || x > sol.bbox.max().x() || y < sol.bbox.min().y() || y > sol.bbox.max().y())
			continue;
		double lo, hi;
		if (!sol.verticalExtent(x, y, lo, hi)) continue;
		const ObjectInfo* oi = scene.object(sol.object_id);
		ext.push_back({lo, hi, sol.object_id, oi && oi->traversable});
	}
	for (const auto& e : ext)
	{
		if (e.trav || e.hi <= s.obstacle_min_height)
		{
			if (e.hi > g)
			{
				g = e.hi;
				supportObj = e.trav ? e.id : supportObj;
			}
		}
	}
	if (support) *support = g;
	double bestTop = -1e9;
	int obstObj = 0;
	for (const auto& e : ext)
	{
		if (e.trav || e.hi <= s.obstacle_min_height) continue;
		if (e.hi > g + s.obstacle_min_height && e.lo < s.robot_height && e.hi > bestTop)
		{
			bestTop = e.hi;
			obstObj = e.id;
		}
	}
	if (obstObj != 0 || bestTop > -1e9)
	{
		obj = obstObj;
		return Label::Obstacle;
	}
	if (g < -s.drop_min_depth)
	{
		obj = negObj;
		return Label::Drop;
	}
	obj = supportObj;
	return Label::Free;
}

void GroundTruthGrid::build(Scene& scene, const GridSpec& s)
{
	spec = s;
	// traversability and categories of the objects
	for (auto& o : scene.objects)
	{
		o.traversable = (o.type == "ramp" && o.slope_deg <= s.max_slope_deg);
		if (o.category_given) continue;
		if (o.type == "hole" || o.type == "stairs_down")
			o.category = Category::Negative;
		else if (o.traversable)
			o.category = Category::Ramp;
		else
		{
			bool over = false;
			double top = 0;
			for (const auto& sol : scene.solids)
				if (sol.object_id == o.id)
				{
					over = over || sol.bbox.min().z() > s.overhang_clearance;
					top = std::max(top, sol.bbox.max().z());
				}
			o.category = over ? Category::Overhang : (top < s.small_max_height ? Category::Small : Category::Large);
		}
	}
	const int nx = s.nx(), ny = s.ny();
	geomLabel.assign(size_t(nx) * size_t(ny), Label::Free);
	objectId.assign(geomLabel.size(), 0);
	observed.assign(geomLabel.size(), 0);
	for (int iy = 0; iy < ny; iy++)
		for (int ix = 0; ix < nx; ix++) labelCell(scene, ix, iy);
}

void GroundTruthGrid::labelCell(const Scene& scene, int ix, int iy)
{
	const GridSpec& s = spec;
	const int k = std::max(1, s.subsamples);
	Label best = Label::Free;
	int bestObj = 0;
	bool first = true;
	for (int a = 0; a < k; a++)
		for (int b = 0; b < k; b++)
		{
			const double x = s.min_x + (ix + (a + 0.5) / k) * s.resolution;
			const double y = s.min_y + (iy + (b + 0.5) / k) * s.resolution;
			int obj;
			const Label l = probe(scene, s, x, y, obj);
			auto rank = [](Label q) { return q == Label::Obstacle ? 2 : (q == Label::Drop ? 1 : 0); };
			if (first || rank(l) > rank(best) || (rank(l) == rank(best) && bestObj == 0 && obj != 0))
			{
				best = l;
				bestObj = obj;
				first = false;
			}
		}
	if (best == Label::Free)
	{
		// A step inside the cell: the support level of its free probes, taken
		// on a lattice that includes the cell's edges (a face between two
		// inner probes of neighbouring cells would fall through the inner
		// lattice), varies by more than obstacle_min_height. The side face
		// of a raised ramp or the end of its plateau: nobody crosses it.
		double lo = std::numeric_limits<double>::infinity(), hi = -lo;
		int hiObj = 0;
		for (int a = 0; a <= k; a++)
			for (int b = 0; b <= k; b++)
			{
				const double x = s.min_x + (ix + double(a) / k) * s.resolution;
				const double y = s.min_y + (iy + double(b) / k) * s.resolution;
				int obj;
				double g = 0;
				if (probe(scene, s, x, y, obj, &g) != Label::Free) continue;
				lo = std::min(lo, g);
				if (g > hi) hi = g, hiObj = obj;
			}
		if (hi - lo > s.obstacle_min_height)
		{
			best = Label::Obstacle;
			bestObj = hiObj;
		}
	}
	geomLabel[idx(ix, iy)] = best;
	objectId[idx(ix, iy)] = bestObj;
}

void GroundTruthGrid::relabel(const Scene& scene, const Eigen::AlignedBox2d& region)
{
	if (region.isEmpty()) return;
	const int nx = spec.nx(), ny = spec.ny();
	const int x0 = std::max(0, int(std::floor((region.min().x() - spec.min_x) / spec.resolution)) - 1);
	const int y0 = std::max(0, int(std::floor((region.min().y() - spec.min_y) / spec.resolution)) - 1);
	const int x1 = std::min(nx - 1, int(std::floor((region.max().x() - spec.min_x) / spec.resolution)) + 1);
	const int y1 = std::min(ny - 1, int(std::floor((region.max().y() - spec.min_y) / spec.resolution)) + 1);
	for (int iy = y0; iy <= y1; iy++)
		for (int ix = x0; ix <= x1; ix++) labelCell(scene, ix, iy);
}

bool GroundTruthGrid::cellOf(double x, double y, int& ix, int& iy) const
{
	ix = int(std::floor((x - spec.min_x) / spec.resolution));
	iy = int(std::floor((y - spec.min_y) / spec.resolution));
	return ix >= 0 && iy >= 0 && ix < spec.nx() && iy < spec.ny();
}

void GroundTruthGrid::markObserved(const std::vector<Eigen::Vector2d>& pts)
{
	int ix, iy;
	for (const auto& p : pts)
		if (cellOf(p.x(), p.y(), ix, iy)) observed[idx(ix, iy)] = 1;
}

Label GroundTruthGrid::label(int ix, int iy) const
{
	const size_t i = idx(ix, iy);
	return observed[i] ? geomLabel[i] : Label::Unobserved;
}

Label GroundTruthGrid::labelAt(double x, double y) const
{
	int ix, iy;
	if (!cellOf(x, y, ix, iy)) return Label::Unobserved;
	return label(ix, iy);
}

int GroundTruthGrid::objectAt(double x, double y) const
{
	int ix, iy;
	if (!cellOf(x, y, ix, iy)) return 0;
	return objectId[idx(ix, iy)];
}

}  // namespace gam::sim
