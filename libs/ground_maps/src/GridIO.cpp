#include <gam/maps/GridIO.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace gam::maps
{
using mrpt::maps::COccupancyGridMap2D;

uint8_t pgmValue(COccupancyGridMap2D::cellType cell)
{
	const double pFree = double(COccupancyGridMap2D::l2p(cell));
	return uint8_t(std::clamp<long>(std::lround(255.0 * pFree), 0, 255));
}

void writeRosMap(
	const COccupancyGridMap2D& g, const std::string& yamlPath, const std::string& pgmPath, const std::string& imageName)
{
	const int W = int(g.getSizeX()), H = int(g.getSizeY());
	{
		std::ofstream f(pgmPath, std::ios::binary);
		if (!f) throw std::runtime_error("cannot write " + pgmPath);
		f << "P5\n# ground-aware-mapper: pixel = round(255*(1-p_occupied)), first row = highest y\n"
		  << W << " " << H << "\n255\n";
		std::vector<char> row(static_cast<size_t>(W));
		for (int r = 0; r < H; r++)
		{
			const auto* src = g.getRow(H - 1 - r);
			for (int x = 0; x < W; x++) row[size_t(x)] = char(pgmValue(src[x]));
			f.write(row.data(), W);
		}
		f.flush();
		if (!f) throw std::runtime_error("cannot write " + pgmPath);
	}
	std::ofstream y(yamlPath);
	if (!y) throw std::runtime_error("cannot write " + yamlPath);
	y << std::setprecision(7);  // float grid geometry: 0.05, not 0.0500000007
	y << "image: " << imageName << "\n"
	  << "mode: scale\n"
	  << "resolution: " << g.getResolution() << "\n"
	  << "origin: [" << g.getXMin() << ", " << g.getYMin() << ", 0.0]\n"
	  << "negate: 0\n"
	  // How map_server (and a ROS planner) reads each pixel, p = P(occupied):
	  // occupied above 0.65, free below 0.25, between: unknown (trinary) or a
	  // scaled cost (scale). One frame of floor gives p = 0.5 - K_g = 0.2 (Table
	  // I, K_g = 0.3; 0.2 to 0.21 after the int8 log-odds), so the free
	  // threshold must exceed it: ROS's customary 0.196 (gmapping's) read such
	  // a cell as not free. One frame of a dense obstacle gives 0.5 + 0.5 K_m =
	  // 0.9 > 0.65; a cell never observed, 0.5, stays between the two.
	  << "occupied_thresh: 0.65\n"
	  << "free_thresh: 0.25\n";
	y.flush();
	if (!y) throw std::runtime_error("cannot write " + yamlPath);
}

void copyGridCells(const COccupancyGridMap2D& from, COccupancyGridMap2D& to)
{
	to.setSize(from.getXMin(), from.getXMax(), from.getYMin(), from.getYMax(), from.getResolution(), 0.5f);
	// setSize rounds the cell count as the source's own setSize did, so the
	// sizes agree; copy row by row within both all the same.
	const unsigned w = std::min(to.getSizeX(), from.getSizeX()), h = std::min(to.getSizeY(), from.getSizeY());
	for (unsigned cy = 0; cy < h; cy++) std::copy_n(from.getRow(int(cy)), w, to.getRow(int(cy)));
}

COccupancyGridMap2D plainCopy(const COccupancyGridMap2D& g) { return COccupancyGridMap2D(g); }

void writePlainGridmapGz(const COccupancyGridMap2D& g, const std::string& path)
{
	writeSerializedGz(plainCopy(g), path);
}

PngView pngViewOf(const COccupancyGridMap2D& g)
{
	const int W = int(g.getSizeX()), H = int(g.getSizeY());
	int x0 = W, x1 = -1, y0 = H, y1 = -1;
	for (int y = 0; y < H; y++)
	{
		const auto* row = g.getRow(y);
		for (int x = 0; x < W; x++)
			if (row[x] != 0)
			{
				x0 = std::min(x0, x);
				x1 = std::max(x1, x);
				y0 = std::min(y0, y);
				y1 = std::max(y1, y);
			}
	}
	PngView v;
	if (x1 < 0)
	{
		v.w = W;
		v.h = H;
	}
	else
	{
		const int m = std::max(1, int(std::ceil(1.0 / g.getResolution())));
		v.cx0 = std::max(0, x0 - m);
		v.cy0 = std::max(0, y0 - m);
		v.w = std::min(W - 1, x1 + m) - v.cx0 + 1;
		v.h = std::min(H - 1, y1 + m) - v.cy0 + 1;
	}
	v.scale = std::clamp(600 / std::max(1, std::max(v.w, v.h)), 1, 8);
	return v;
}

void writeGridPng(const COccupancyGridMap2D& g, const std::string& path, const PngStyle& style)
{
	const PngView v = pngViewOf(g);
	const int k = v.scale;
	const int strip = style.legend ? 40 : 0;  // scale bar + legend below the map
	const int W = std::max(v.w * k, style.legend ? 430 : 1);
	mrpt::img::CImage im(W, v.h * k + strip, mrpt::img::CH_RGB);
	im.filledRectangle(0, 0, W - 1, v.h * k + strip - 1, mrpt::img::TColor(255, 255, 255));
	const COccupancyGridMap2D* L = style.missing;
	const bool layerFits = L && L->getSizeX() == g.getSizeX() && L->getSizeY() == g.getSizeY();
	for (int r = 0; r < v.h; r++)
	{
		const int cy = v.cy0 + v.h - 1 - r;
		const auto* src = g.getRow(cy);
		const auto* lay = layerFits ? L->getRow(cy) : nullptr;
		for (int x = 0; x < v.w; x++)
		{
			const auto cell = src[v.cx0 + x];
			mrpt::img::TColor c(kUnknownR, kUnknownG, kUnknownB);
			if (lay && COccupancyGridMap2D::l2p(lay[v.cx0 + x]) < 0.5f)
				c = mrpt::img::TColor(kMissingR, kMissingG, kMissingB);
			else if (cell != 0)
			{
				const uint8_t p = pgmValue(cell);
				c = mrpt::img::TColor(p, p, p);
			}
			for (int dy = 0; dy < k; dy++)
				for (int dx = 0; dx < k; dx++) im.setPixel(x * k + dx, r * k + dy, c);
		}
	}
	if (style.legend)
	{
		using mrpt::img::TColor;
		const int y0 = v.h * k;
		// 1 m scale bar.
		const int bar = int(std::lround(1.0 / g.getResolution() * k));
		im.filledRectangle(6, y0 + 4, 6 + bar, y0 + 7, TColor(0, 90, 200));
		im.textOut(10 + bar, y0 + 1, "1 m", TColor(0, 90, 200));
		int x = 6;
		const int y = y0 + 22;
		const auto swatch = [&](const TColor& c, const std::string& text) {
			im.filledRectangle(x, y, x + 12, y + 12, c);
			im.rectangle(x, y, x + 12, y + 12, TColor(120, 120, 120));
			im.textOut(x + 16, y + 2, text, TColor(0, 0, 0));
			x += 16 + 9 * int(text.size()) + 14;
		};
		swatch(TColor(255, 255, 255), "free");
		swatch(TColor(0, 0, 0), "occupied");
		swatch(TColor(kUnknownR, kUnknownG, kUnknownB), "unknown");
		if (L) swatch(TColor(kMissingR, kMissingG, kMissingB), "missing floor");
	}
	if (!im.saveToFile(path)) throw std::runtime_error("cannot write " + path);
}

bool recentreGrid(COccupancyGridMap2D& g, double cx, double cy, int n)
{
	const double res = g.getResolution();
	const double ox = g.getXMin(), oy = g.getYMin();
	const long sx = std::lround((cx - 0.5 * n * res - ox) / res);
	const long sy = std::lround((cy - 0.5 * n * res - oy) / res);
	if (sx == 0 && sy == 0 && int(g.getSizeX()) == n && int(g.getSizeY()) == n) return false;
	const COccupancyGridMap2D old = plainCopy(g);
	const float nx0 = float(ox + sx * res), ny0 = float(oy + sy * res);
	g.setSize(nx0, float(nx0 + n * res), ny0, float(ny0 + n * res), float(res), 0.5f);
	const int W = int(g.getSizeX()), H = int(g.getSizeY());
	const int oW = int(old.getSizeX()), oH = int(old.getSizeY());
	for (int y = 0; y < H; y++)
	{
		const long oyIdx = long(y) + sy;
		if (oyIdx < 0 || oyIdx >= oH) continue;
		auto* dst = g.getRow(y);
		const auto* src = old.getRow(int(oyIdx));
		for (int x = 0; x < W; x++)
		{
			const long oxIdx = long(x) + sx;
			if (oxIdx >= 0 && oxIdx < oW) dst[x] = src[oxIdx];
		}
	}
	return true;
}

// ---------------------------------------------------------------------------
COccupancyGridMap2D readGridmapGz(const std::string& path)
{
	mrpt::io::CFileGZInputStream f;
	if (!f.open(path)) throw std::runtime_error("cannot open " + path);
	COccupancyGridMap2D g;
	auto ar = mrpt::serialization::archiveFrom(f);
	ar >> g;
	return g;
}

COccupancyGridMap2D readStockGrid(const std::string& path)
{
	const auto endsWith = [&](const char* ext) {
		const std::string e(ext);
		return path.size() >= e.size() && std::equal(e.rbegin(), e.rend(), path.rbegin(), [](char a, char b) {
				   return std::tolower(static_cast<unsigned char>(a)) == b;
			   });
	};
	if (!std::ifstream(path)) throw std::runtime_error("cannot open " + path);
	COccupancyGridMap2D g;
	if (endsWith(".yaml") || endsWith(".yml"))
	{
		// MRPT prints the reason (with a call stack) on std::cerr and returns
		// false: keep its "Message:" line for our one-line error.
		std::ostringstream mrptSays;
		std::streambuf* const cerrBuf = std::cerr.rdbuf(mrptSays.rdbuf());
		bool ok = false;
		try
		{
			ok = g.loadFromROSMapServerYAML(path);
		}
		catch (...)
		{
		}
		std::cerr.rdbuf(cerrBuf);
		if (!ok)
		{
			std::string why = mrptSays.str();
			const auto m = why.find("Message:");
			why = m == std::string::npos ? "" : why.substr(m + 8, why.find('\n', m) - m - 8);
			throw std::runtime_error(
				path +
				": not a ROS map_server map (needs image, resolution, origin, occupied_thresh, free_thresh, "
				"negate)" +
				(why.empty() ? "" : ":" + why));
		}
		return g;
	}
	mrpt::io::CFileGZInputStream f;
	if (!f.open(path)) throw std::runtime_error("cannot open " + path);
	mrpt::serialization::CSerializable::Ptr obj;
	try
	{
		auto ar = mrpt::serialization::archiveFrom(f);
		obj = ar.ReadObject();
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(
			path + ": not a serialized MRPT object (" + std::string(e.what()).substr(0, 200) + ")");
	}
	const auto* grid = dynamic_cast<const COccupancyGridMap2D*>(obj.get());
	if (!grid)
		throw std::runtime_error(
			path + " holds a " + obj->GetRuntimeClass()->className + ", not an occupancy grid (COccupancyGridMap2D)");
	return COccupancyGridMap2D(*grid);  // a derived class: its grid part
}

void writeSerializedGz(const mrpt::serialization::CSerializable& obj, const std::string& path)
{
	mrpt::io::CFileGZOutputStream f;
	if (!f.open(path, 6)) throw std::runtime_error("cannot write " + path);
	auto ar = mrpt::serialization::archiveFrom(f);
	ar << obj;
	f.close();
}

}  // namespace gam::maps
