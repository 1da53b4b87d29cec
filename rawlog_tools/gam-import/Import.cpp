// Ground-aware mapping for MRPT -- gam-import: parsing and conversion (see Import.h).
#include "Import.h"

#include <mrpt/math/CQuaternion.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

namespace gam::import
{
namespace
{
std::string trim(std::string s)
{
	const auto b = s.find_first_not_of(" \t\r\n");
	if (b == std::string::npos) return "";
	const auto e = s.find_last_not_of(" \t\r\n");
	return s.substr(b, e - b + 1);
}

std::vector<std::string> tokens(const std::string& s)
{
	std::istringstream is(s);
	std::vector<std::string> out;
	std::string t;
	while (is >> t) out.push_back(t);
	return out;
}

/** A whole-token number ("nan" and "inf" parse; the caller checks finiteness). */
bool toDouble(const std::string& s, double& v)
{
	if (s.empty()) return false;
	char* end = nullptr;
	v = std::strtod(s.c_str(), &end);
	return end && *end == '\0';
}

double number(const std::string& s, const std::string& where)
{
	double v = 0;
	if (!toDouble(s, v) || !std::isfinite(v)) throw ImportError(where + ": '" + s + "' is not a finite number");
	return v;
}

std::vector<double> numbers(const std::string& text, size_t n, const std::string& where, const std::string& what)
{
	const auto t = tokens(text);
	if (t.size() != n)
		throw ImportError(
			where + ": expected " + std::to_string(n) + " numbers (" + what + "), got " + std::to_string(t.size()));
	std::vector<double> v;
	for (const auto& s : t) v.push_back(number(s, where));
	return v;
}

std::string fmt(double v)
{
	std::ostringstream os;
	os << v;
	return os.str();
}

void requireFile(const std::string& path, const std::string& what)
{
	if (!mrpt::system::fileExists(path)) throw ImportError("missing file: " + path + " (" + what + ")");
}

/** Lines without comments ('#' anywhere; ';' too when `semicolon`), numbered from 1. */
std::vector<std::pair<int, std::string>> contentLines(const std::string& path, bool semicolon)
{
	std::ifstream f(path);
	if (!f) throw ImportError("cannot read " + path);
	std::vector<std::pair<int, std::string>> out;
	std::string l;
	int n = 0;
	while (std::getline(f, l))
	{
		n++;
		auto c = l.find('#');
		if (semicolon) c = std::min(c, l.find(';'));
		if (c != std::string::npos) l.erase(c);
		l = trim(l);
		if (!l.empty()) out.emplace_back(n, l);
	}
	return out;
}
}  // namespace

void checkIntrinsics(const Intrinsics& k, const std::string& where)
{
	if (k.width <= 0 || k.height <= 0 || k.width > 65535 || k.height > 65535)
		throw ImportError(
			where + ": image size " + std::to_string(k.width) + "x" + std::to_string(k.height) + " is not valid");
	if (!(k.fx > 0) || !(k.fy > 0) || !std::isfinite(k.fx) || !std::isfinite(k.fy))
		throw ImportError(where + ": fx and fy must be > 0 (got " + fmt(k.fx) + ", " + fmt(k.fy) + ")");
	if (!(k.cx >= 0 && k.cx < k.width))
		throw ImportError(
			where + ": cx = " + fmt(k.cx) + " is outside the image (width " + std::to_string(k.width) + ")");
	if (!(k.cy >= 0 && k.cy < k.height))
		throw ImportError(
			where + ": cy = " + fmt(k.cy) + " is outside the image (height " + std::to_string(k.height) + ")");
}

mrpt::poses::CPose3D parseSensorPose(const std::string& text, const std::string& where)
{
	const auto v = numbers(text, 6, where, "x y z [m] yaw pitch roll [deg]");
	const double d = M_PI / 180.0;
	return mrpt::poses::CPose3D(v[0], v[1], v[2], v[3] * d, v[4] * d, v[5] * d);
}

Intrinsics parseIntrinsics(const std::string& text, const std::string& where)
{
	const auto v = numbers(text, 6, where, "width height fx fy cx cy");
	if (v[0] != std::floor(v[0]) || v[1] != std::floor(v[1]))
		throw ImportError(where + ": width and height must be integers");
	Intrinsics k{int(v[0]), int(v[1]), v[2], v[3], v[4], v[5]};
	checkIntrinsics(k, where);
	return k;
}

CameraConfig readCameraIni(const std::string& path)
{
	requireFile(path, "camera .ini");
	CameraConfig c;
	std::map<std::string, double> k;
	const std::vector<std::string> intrinsicKeys = {"width", "height", "fx", "fy", "cx", "cy"};
	for (const auto& [n, line] : contentLines(path, true))
	{
		const std::string where = path + ":" + std::to_string(n);
		if (line.front() == '[')
		{
			if (line != "[camera]") throw ImportError(where + ": unknown section " + line + " (only [camera])");
			continue;
		}
		const auto eq = line.find('=');
		if (eq == std::string::npos) throw ImportError(where + ": expected 'key = value'");
		const std::string key = trim(line.substr(0, eq)), value = trim(line.substr(eq + 1));
		if (std::find(intrinsicKeys.begin(), intrinsicKeys.end(), key) != intrinsicKeys.end())
			k[key] = number(value, where);
		else if (key == "depth_scale")
		{
			c.depthScale = number(value, where);
			if (!(*c.depthScale > 0)) throw ImportError(where + ": depth_scale must be > 0");
		}
		else if (key == "sensor_pose")
			c.sensorPose = parseSensorPose(value, where);
		else if (key == "label")
		{
			if (value.empty()) throw ImportError(where + ": empty label");
			c.label = value;
		}
		else
			throw ImportError(
				where + ": unknown key '" + key + "' (width height fx fy cx cy depth_scale sensor_pose label)");
	}
	if (!k.empty())
	{
		std::string missing;
		for (const auto& key : intrinsicKeys)
			if (!k.count(key)) missing += " " + key;
		if (!missing.empty()) throw ImportError(path + ": intrinsics incomplete, missing:" + missing);
		if (k["width"] != std::floor(k["width"]) || k["height"] != std::floor(k["height"]))
			throw ImportError(path + ": width and height must be integers");
		Intrinsics in{int(k["width"]), int(k["height"]), k["fx"], k["fy"], k["cx"], k["cy"]};
		checkIntrinsics(in, path);
		c.intrinsics = in;
	}
	return c;
}

// ------------------------------------------------------------------ poses

mrpt::poses::CPose3D opticalInSensorFrame() { return mrpt::poses::CPose3D(0, 0, 0, -M_PI / 2, 0, -M_PI / 2); }

mrpt::poses::CPose3D poseFromTum(double tx, double ty, double tz, double qx, double qy, double qz, double qw)
{
	const double n = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
	if (!std::isfinite(n) || std::abs(n - 1) > 0.01)
		throw ImportError("quaternion (qx qy qz qw) of norm " + fmt(n) + " is not a unit quaternion");
	mrpt::math::CQuaternionDouble q(qw / n, qx / n, qy / n, qz / n);
	return mrpt::poses::CPose3D(q, tx, ty, tz);
}

mrpt::poses::CPose3D robotFromCamera(const mrpt::poses::CPose3D& worldOptical, const mrpt::poses::CPose3D& sensorPose)
{
	const mrpt::poses::CPose3D robotOptical = sensorPose + opticalInSensorFrame();
	return worldOptical + (-robotOptical);
}

mrpt::poses::CPose2D to2D(const mrpt::poses::CPose3D& p) { return mrpt::poses::CPose2D(p.x(), p.y(), p.yaw()); }

std::vector<TimedPose> readGroundTruth(const std::string& path)
{
	requireFile(path, "ground truth, TUM format: timestamp tx ty tz qx qy qz qw");
	std::vector<TimedPose> out;
	for (const auto& [n, line] : contentLines(path, false))
	{
		const std::string where = path + " line " + std::to_string(n);
		const auto v = numbers(line, 8, where, "timestamp tx ty tz qx qy qz qw");
		if (!out.empty() && !(v[0] > out.back().t))
			throw ImportError(
				where + ": timestamp " + fmt(v[0]) + " is not after the previous one (" + fmt(out.back().t) +
				"): timestamps out of order");
		try
		{
			out.push_back({v[0], poseFromTum(v[1], v[2], v[3], v[4], v[5], v[6], v[7])});
		}
		catch (const ImportError& e)
		{
			throw ImportError(where + ": " + e.what());
		}
	}
	if (out.empty()) throw ImportError(path + ": no poses");
	return out;
}

std::optional<mrpt::poses::CPose3D> poseAt(const std::vector<TimedPose>& gt, double t, double maxGap)
{
	const auto it = std::lower_bound(gt.begin(), gt.end(), t, [](const TimedPose& p, double v) { return p.t < v; });
	if (it != gt.end() && it->t == t) return it->pose;
	if (it == gt.end() || it == gt.begin()) return std::nullopt;
	const TimedPose& a = *(it - 1);
	const TimedPose& b = *it;
	if (t - a.t > maxGap || b.t - t > maxGap) return std::nullopt;
	const double s = (t - a.t) / (b.t - a.t);
	mrpt::math::CQuaternionDouble qa, qb;
	a.pose.getAsQuaternion(qa);
	b.pose.getAsQuaternion(qb);
	double d = qa.r() * qb.r() + qa.x() * qb.x() + qa.y() * qb.y() + qa.z() * qb.z();
	double sb = 1;
	if (d < 0)
	{
		d = -d;
		sb = -1;
	}
	double wa = 1 - s, wb = s;
	if (d < 0.9995)
	{
		const double th = std::acos(d);
		wa = std::sin((1 - s) * th) / std::sin(th);
		wb = std::sin(s * th) / std::sin(th);
	}
	wb *= sb;
	double r = wa * qa.r() + wb * qb.r(), x = wa * qa.x() + wb * qb.x(), y = wa * qa.y() + wb * qb.y(),
		   z = wa * qa.z() + wb * qb.z();
	const double n = std::sqrt(r * r + x * x + y * y + z * z);
	mrpt::math::CQuaternionDouble q(r / n, x / n, y / n, z / n);
	return mrpt::poses::CPose3D(
		q, a.pose.x() + s * (b.pose.x() - a.pose.x()), a.pose.y() + s * (b.pose.y() - a.pose.y()),
		a.pose.z() + s * (b.pose.z() - a.pose.z()));
}

// ------------------------------------------------------------ frame lists

std::vector<ListEntry> readFrameList(const std::string& path)
{
	requireFile(path, "frame list: 'timestamp filename' lines");
	std::vector<ListEntry> out;
	for (const auto& [n, line] : contentLines(path, false))
	{
		const std::string where = path + " line " + std::to_string(n);
		const auto t = tokens(line);
		ListEntry e;
		e.line = n;
		if (t.size() == 2)
		{
			e.t = number(t[0], where);
			e.file = t[1];
		}
		else if (t.size() == 4)
		{
			const bool d1 = t[1].find("depth") != std::string::npos, d3 = t[3].find("depth") != std::string::npos;
			if (d1 == d3)
				throw ImportError(
					where + ": associations line, but not exactly one of its two files has 'depth' in its name");
			e.t = number(t[d1 ? 0 : 2], where);
			e.file = t[d1 ? 1 : 3];
		}
		else
			throw ImportError(where + ": expected 'timestamp filename' (or 't1 file1 t2 file2' associations)");
		if (!out.empty() && !(e.t > out.back().t))
			throw ImportError(
				where + ": timestamp " + fmt(e.t) + " is not after the previous one (" + fmt(out.back().t) +
				"): timestamps out of order");
		out.push_back(e);
	}
	if (out.empty()) throw ImportError(path + ": no frames listed");
	return out;
}

namespace
{
/** Natural order: digit runs compare as numbers ("f2" < "f10"). */
bool naturalLess(const std::string& a, const std::string& b)
{
	size_t i = 0, j = 0;
	while (i < a.size() && j < b.size())
	{
		if (std::isdigit((unsigned char)a[i]) && std::isdigit((unsigned char)b[j]))
		{
			size_t i2 = i, j2 = j;
			while (i2 < a.size() && std::isdigit((unsigned char)a[i2])) i2++;
			while (j2 < b.size() && std::isdigit((unsigned char)b[j2])) j2++;
			std::string na = a.substr(i, i2 - i), nb = b.substr(j, j2 - j);
			na.erase(0, std::min(na.find_first_not_of('0'), na.size()));
			nb.erase(0, std::min(nb.find_first_not_of('0'), nb.size()));
			if (na.size() != nb.size()) return na.size() < nb.size();
			if (na != nb) return na < nb;
			i = i2;
			j = j2;
		}
		else
		{
			if (a[i] != b[j]) return a[i] < b[j];
			i++;
			j++;
		}
	}
	return a.size() - i < b.size() - j || (a.size() - i == b.size() - j && a < b);
}
}  // namespace

std::vector<std::string> listFolder(const std::string& dir, const std::string& ext)
{
	namespace fs = std::filesystem;
	std::error_code ec;
	if (!fs::is_directory(dir, ec)) throw ImportError("missing folder: " + dir);
	std::vector<std::string> names;
	for (const auto& e : fs::directory_iterator(dir, ec))
	{
		if (!e.is_regular_file()) continue;
		std::string n = e.path().filename().string(), lower = n;
		for (auto& ch : lower) ch = char(std::tolower((unsigned char)ch));
		if (lower.size() > ext.size() && lower.compare(lower.size() - ext.size(), ext.size(), ext) == 0)
			names.push_back(n);
	}
	if (ec) throw ImportError("cannot list folder " + dir + ": " + ec.message());
	std::sort(names.begin(), names.end(), naturalLess);
	if (names.empty()) throw ImportError("no *" + ext + " files in " + dir);
	return names;
}

// -------------------------------------------------------------- depth PNG

DepthFrame loadDepthPng(const std::string& path, const Intrinsics& k, double depthScale)
{
	requireFile(path, "depth PNG");
	if (!(depthScale > 0) || !std::isfinite(depthScale)) throw ImportError("depth scale must be > 0");
	{
		std::ifstream f(path, std::ios::binary);
		unsigned char sig[8] = {0};
		f.read(reinterpret_cast<char*>(sig), 8);
		static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
		if (!f || std::memcmp(sig, png, 8) != 0) throw ImportError(path + ": not a PNG file");
	}
	mrpt::img::CImage im;
	if (!im.loadFromFile(path, -1) || im.isEmpty()) throw ImportError(path + ": cannot decode the PNG");
	const int ch = int(im.getChannelCount());
	const auto depth = im.getPixelDepth();
	if (depth != mrpt::img::PixelDepth::D16U || ch != 1)
	{
		const char* bits = depth == mrpt::img::PixelDepth::D8U || depth == mrpt::img::PixelDepth::D8S ? "8-bit"
						   : depth == mrpt::img::PixelDepth::D16U                                     ? "16-bit"
																									  : "non-integer";
		throw ImportError(
			path + ": " + bits + " image with " + std::to_string(ch) +
			" channel(s); a depth PNG must be 16-bit with 1 channel");
	}
	const int w = int(im.getWidth()), h = int(im.getHeight());
	if (w != k.width || h != k.height)
		throw ImportError(
			path + ": image is " + std::to_string(w) + "x" + std::to_string(h) + " but the intrinsics are for " +
			std::to_string(k.width) + "x" + std::to_string(k.height));
	DepthFrame f;
	f.k = k;
	f.units = float(1.0 / depthScale);
	f.range.resize(h, w);
	for (int r = 0; r < h; r++)
	{
		const uint16_t* row = im.ptr<uint16_t>(0, r);
		for (int c = 0; c < w; c++) f.range(r, c) = row[c];
	}
	return f;
}

// -------------------------------------------------------------------- PCD

std::vector<uint8_t> lzfDecompress(const uint8_t* in, size_t inSize, size_t outSize)
{
	std::vector<uint8_t> out(outSize);
	size_t ip = 0, op = 0;
	auto corrupt = [](const char* why) { return ImportError(std::string("corrupt LZF data (") + why + ")"); };
	while (ip < inSize)
	{
		const unsigned ctrl = in[ip++];
		if (ctrl < 32)
		{  // literal run of ctrl + 1 bytes
			const size_t len = ctrl + 1;
			if (op + len > outSize) throw corrupt("output overrun");
			if (ip + len > inSize) throw corrupt("input overrun");
			std::memcpy(out.data() + op, in + ip, len);
			op += len;
			ip += len;
		}
		else
		{  // back reference: length (ctrl >> 5) + 2, offset from 13 bits + 1
			size_t len = ctrl >> 5;
			if (len == 7)
			{
				if (ip >= inSize) throw corrupt("input overrun");
				len += in[ip++];
			}
			if (ip >= inSize) throw corrupt("input overrun");
			const size_t back = ((size_t(ctrl & 0x1f) << 8) | in[ip++]) + 1;
			len += 2;
			if (back > op) throw corrupt("back reference before the start");
			if (op + len > outSize) throw corrupt("output overrun");
			for (size_t i = 0; i < len; i++, op++) out[op] = out[op - back];  // may overlap
		}
	}
	if (op != outSize)
		throw ImportError(
			"corrupt LZF data (" + std::to_string(op) + " bytes decompressed, header says " + std::to_string(outSize) +
			")");
	return out;
}

namespace
{
struct PcdField
{
	std::string name;
	int size = 4, count = 1;
	char type = 'F';
	size_t offset = 0;  ///< within a point (binary) / per-point position of the field
};

double readScalar(const uint8_t* p, const PcdField& f)
{
	if (f.type == 'F')
	{
		if (f.size == 4)
		{
			float v;
			std::memcpy(&v, p, 4);
			return v;
		}
		double v;
		std::memcpy(&v, p, 8);
		return v;
	}
	return 0;  // x/y/z are checked to be F
}
}  // namespace

PcdCloud readPcd(const std::string& path)
{
	requireFile(path, "PCD");
	std::ifstream f(path, std::ios::binary);
	if (!f) throw ImportError("cannot read " + path);
	const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());

	std::vector<PcdField> fields;
	std::vector<int> sizes, counts;
	std::vector<char> types;
	long long width = -1, height = -1, points = -1;
	std::string data;
	size_t pos = 0;
	while (data.empty())
	{
		if (pos >= bytes.size()) throw ImportError(path + ": not a PCD file (no DATA line in the header)");
		size_t e = bytes.find('\n', pos);
		if (e == std::string::npos) e = bytes.size();
		const std::string line = trim(bytes.substr(pos, e - pos));
		pos = e + 1;
		if (line.empty() || line[0] == '#') continue;
		const auto t = tokens(line);
		const std::string& key = t[0];
		auto ints = [&](std::vector<int>& out) {
			for (size_t i = 1; i < t.size(); i++)
			{
				double v = 0;
				if (!toDouble(t[i], v) || v != std::floor(v) || v < 0 || v > 1e9)
					throw ImportError(path + ": bad " + key + " value '" + t[i] + "'");
				out.push_back(int(v));
			}
		};
		auto one = [&]() -> long long {
			double v = 0;
			if (t.size() != 2 || !toDouble(t[1], v) || v != std::floor(v) || v < 0 || v > 1e9)
				throw ImportError(path + ": bad " + key + " line '" + line + "'");
			return (long long)v;
		};
		if (key == "VERSION" || key == "VIEWPOINT")
			continue;
		else if (key == "FIELDS")
			for (size_t i = 1; i < t.size(); i++) fields.push_back({t[i]});
		else if (key == "SIZE")
			ints(sizes);
		else if (key == "COUNT")
			ints(counts);
		else if (key == "TYPE")
		{
			for (size_t i = 1; i < t.size(); i++)
			{
				if (t[i].size() != 1 || std::string("FUI").find(t[i][0]) == std::string::npos)
					throw ImportError(path + ": bad TYPE '" + t[i] + "'");
				types.push_back(t[i][0]);
			}
		}
		else if (key == "WIDTH")
			width = one();
		else if (key == "HEIGHT")
			height = one();
		else if (key == "POINTS")
			points = one();
		else if (key == "DATA")
		{
			if (t.size() != 2) throw ImportError(path + ": bad DATA line");
			data = t[1];
		}
		else
			throw ImportError(path + ": not a PCD file (unexpected header line '" + line.substr(0, 40) + "')");
	}
	if (data != "ascii" && data != "binary" && data != "binary_compressed")
		throw ImportError(path + ": DATA " + data + " is not ascii, binary or binary_compressed");
	if (fields.empty() || sizes.size() != fields.size() || types.size() != fields.size() ||
		(!counts.empty() && counts.size() != fields.size()))
		throw ImportError(path + ": FIELDS, SIZE, TYPE and COUNT do not have the same number of entries");
	if (width <= 0 || height < 0) throw ImportError(path + ": missing or bad WIDTH / HEIGHT");
	if (height <= 1)
		throw ImportError(
			path + ": unorganized cloud (HEIGHT " + std::to_string(height) +
			"); gam-import needs an organized cloud (one point per depth pixel)");
	const size_t n = size_t(width) * size_t(height);
	if (n > 100'000'000) throw ImportError(path + ": " + std::to_string(n) + " points is too many");
	if (points >= 0 && size_t(points) != n)
		throw ImportError(
			path + ": POINTS " + std::to_string(points) + " is not WIDTH x HEIGHT = " + std::to_string(n));
	size_t stride = 0;
	for (size_t i = 0; i < fields.size(); i++)
	{
		auto& fd = fields[i];
		fd.size = sizes[i];
		fd.type = types[i];
		fd.count = counts.empty() ? 1 : counts[i];
		if (fd.size != 1 && fd.size != 2 && fd.size != 4 && fd.size != 8)
			throw ImportError(path + ": field " + fd.name + " has SIZE " + std::to_string(fd.size));
		if (fd.count < 1 || fd.count > 100000)
			throw ImportError(path + ": field " + fd.name + " has COUNT " + std::to_string(fd.count));
		fd.offset = stride;
		stride += size_t(fd.size) * size_t(fd.count);
	}
	auto find = [&](const std::string& name) -> const PcdField* {
		for (const auto& fd : fields)
			if (fd.name == name) return &fd;
		return nullptr;
	};
	const PcdField *fx = find("x"), *fy = find("y"), *fz = find("z");
	if (!fx || !fy || !fz) throw ImportError(path + ": the cloud has no x, y and z fields");
	for (const PcdField* p : {fx, fy, fz})
		if (p->type != 'F' || (p->size != 4 && p->size != 8) || p->count != 1)
			throw ImportError(path + ": field " + p->name + " must be TYPE F, SIZE 4 or 8, COUNT 1");
	const PcdField* fc = find("rgb");
	if (!fc) fc = find("rgba");
	if (fc && (fc->size != 4 || fc->count != 1)) fc = nullptr;  // not the packed PCL colour: ignored

	PcdCloud c;
	c.width = int(width);
	c.height = int(height);
	c.dataKind = data;
	c.x.resize(n);
	c.y.resize(n);
	c.z.resize(n);
	if (fc) c.rgb.resize(n);

	if (data == "ascii")
	{
		std::istringstream is(bytes.substr(pos));
		std::string line;
		size_t i = 0;
		std::vector<std::string> t;
		while (i < n && std::getline(is, line))
		{
			t = tokens(line);
			if (t.empty()) continue;
			// ASCII: one token per element (COUNT elements per field, in order)
			size_t tok = 0;
			for (const auto& fd : fields)
			{
				if (tok + size_t(fd.count) > t.size())
					throw ImportError(path + ": point " + std::to_string(i) + " has too few values");
				double v = 0;
				if (&fd == fx || &fd == fy || &fd == fz || &fd == fc)
				{
					if (!toDouble(t[tok], v))
						throw ImportError(path + ": point " + std::to_string(i) + ": bad value '" + t[tok] + "'");
					if (&fd == fx) c.x[i] = float(v);
					if (&fd == fy) c.y[i] = float(v);
					if (&fd == fz) c.z[i] = float(v);
					if (&fd == fc)
					{
						uint32_t bits = 0;
						if (fd.type == 'F')
						{
							const float fv = float(v);
							std::memcpy(&bits, &fv, 4);
						}
						else
							bits = uint32_t(int64_t(v));
						c.rgb[i] = bits & 0xFFFFFF;
					}
				}
				tok += size_t(fd.count);
			}
			i++;
		}
		if (i != n)
			throw ImportError(
				path + ": truncated: " + std::to_string(i) + " of " + std::to_string(n) + " points in the file");
		return c;
	}

	const uint8_t* raw = reinterpret_cast<const uint8_t*>(bytes.data()) + pos;
	const size_t rawSize = pos <= bytes.size() ? bytes.size() - pos : 0;
	std::vector<uint8_t> unpacked;
	// binary: point after point; binary_compressed: field after field (each
	// field's values for all points), LZF-compressed.
	const bool columnwise = data == "binary_compressed";
	const uint8_t* base = raw;
	if (!columnwise)
	{
		if (rawSize < n * stride)
			throw ImportError(
				path + ": truncated: " + std::to_string(rawSize) + " data bytes, " + std::to_string(n * stride) +
				" expected");
	}
	else
	{
		if (rawSize < 8) throw ImportError(path + ": truncated: no compressed data header");
		uint32_t compressed = 0, uncompressed = 0;
		std::memcpy(&compressed, raw, 4);
		std::memcpy(&uncompressed, raw + 4, 4);
		if (uncompressed != n * stride)
			throw ImportError(
				path + ": compressed data holds " + std::to_string(uncompressed) + " bytes, the header needs " +
				std::to_string(n * stride));
		if (size_t(compressed) > rawSize - 8)
			throw ImportError(
				path + ": truncated: " + std::to_string(rawSize - 8) + " compressed bytes, header says " +
				std::to_string(compressed));
		try
		{
			unpacked = lzfDecompress(raw + 8, compressed, uncompressed);
		}
		catch (const ImportError& e)
		{
			throw ImportError(path + ": " + e.what());
		}
		base = unpacked.data();
	}
	auto start = [&](const PcdField& fd) { return columnwise ? fd.offset * n : fd.offset; };
	auto elemStep = [&](const PcdField& fd) { return columnwise ? size_t(fd.size) * size_t(fd.count) : stride; };
	for (const PcdField* p : {fx, fy, fz})
	{
		std::vector<float>& dst = p == fx ? c.x : p == fy ? c.y : c.z;
		const uint8_t* q = base + start(*p);
		const size_t step = elemStep(*p);
		for (size_t i = 0; i < n; i++, q += step) dst[i] = float(readScalar(q, *p));
	}
	if (fc)
	{
		const uint8_t* q = base + start(*fc);
		const size_t step = elemStep(*fc);
		for (size_t i = 0; i < n; i++, q += step)
		{
			uint32_t bits;
			std::memcpy(&bits, q, 4);
			c.rgb[i] = bits & 0xFFFFFF;
		}
	}
	return c;
}

IntrinsicsFit fitIntrinsics(const PcdCloud& c)
{
	// Two 1D regressions: u on a = x/z (slope fx, intercept cx), v on b = y/z.
	const size_t n = size_t(c.width) * size_t(c.height);
	auto valid = [&](size_t i) {
		return std::isfinite(c.x[i]) && std::isfinite(c.y[i]) && std::isfinite(c.z[i]) && c.z[i] > 0;
	};
	double sa = 0, su = 0, sb = 0, sv = 0;
	size_t m = 0;
	for (size_t i = 0; i < n; i++)
		if (valid(i))
		{
			sa += double(c.x[i]) / c.z[i];
			sb += double(c.y[i]) / c.z[i];
			su += double(i % size_t(c.width));
			sv += double(i / size_t(c.width));
			m++;
		}
	if (m < 3) throw ImportError("fewer than 3 valid points: cannot fit the intrinsics");
	const double ma = sa / double(m), mb = sb / double(m), mu = su / double(m), mv = sv / double(m);
	double saa = 0, sau = 0, sbb = 0, sbv = 0;
	for (size_t i = 0; i < n; i++)
		if (valid(i))
		{
			const double a = double(c.x[i]) / c.z[i] - ma, b = double(c.y[i]) / c.z[i] - mb;
			saa += a * a;
			sau += a * (double(i % size_t(c.width)) - mu);
			sbb += b * b;
			sbv += b * (double(i / size_t(c.width)) - mv);
		}
	if (!(saa > 1e-12) || !(sbb > 1e-12))
		throw ImportError("the valid points span a single column or row: cannot fit the intrinsics");
	IntrinsicsFit fit;
	fit.k.width = c.width;
	fit.k.height = c.height;
	fit.k.fx = sau / saa;
	fit.k.cx = mu - fit.k.fx * ma;
	fit.k.fy = sbv / sbb;
	fit.k.cy = mv - fit.k.fy * mb;
	fit.points = m;
	double ss = 0;
	for (size_t i = 0; i < n; i++)
		if (valid(i))
		{
			const double du = fit.k.fx * c.x[i] / c.z[i] + fit.k.cx - double(i % size_t(c.width));
			const double dv = fit.k.fy * c.y[i] / c.z[i] + fit.k.cy - double(i / size_t(c.width));
			ss += du * du + dv * dv;
			fit.max_px = std::max({fit.max_px, std::abs(du), std::abs(dv)});
		}
	fit.rms_px = std::sqrt(ss / double(2 * m));
	return fit;
}

DepthFrame depthFromPcd(const PcdCloud& c, const Intrinsics& k, float units, size_t* dropped)
{
	if (k.width != c.width || k.height != c.height)
		throw ImportError(
			"intrinsics for " + std::to_string(k.width) + "x" + std::to_string(k.height) + " but the cloud is " +
			std::to_string(c.width) + "x" + std::to_string(c.height));
	if (!(units > 0)) throw ImportError("range units must be > 0");
	DepthFrame f;
	f.k = k;
	f.units = units;
	f.range.resize(c.height, c.width);
	size_t drop = 0;
	for (int r = 0; r < c.height; r++)
		for (int col = 0; col < c.width; col++)
		{
			const size_t i = size_t(r) * size_t(c.width) + size_t(col);
			const double z = c.z[i];
			uint16_t v = 0;
			if (std::isfinite(z) && z > 0 && std::isfinite(c.x[i]) && std::isfinite(c.y[i]))
			{
				const double q = std::round(z / double(units));
				if (q >= 1 && q <= 65535)
					v = uint16_t(q);
				else
					drop++;
			}
			f.range(r, col) = v;
		}
	if (dropped) *dropped = drop;
	if (!c.rgb.empty())
	{
		mrpt::img::CImage im(c.width, c.height, mrpt::img::CH_RGB);
		for (int r = 0; r < c.height; r++)
		{
			uint8_t* row = im.ptr<uint8_t>(0, r);
			for (int col = 0; col < c.width; col++)
			{
				const uint32_t p = c.rgb[size_t(r) * size_t(c.width) + size_t(col)];
				row[3 * col + 0] = uint8_t(p & 0xFF);  // CImage colour is BGR in memory
				row[3 * col + 1] = uint8_t((p >> 8) & 0xFF);
				row[3 * col + 2] = uint8_t((p >> 16) & 0xFF);
			}
		}
		f.rgb = std::move(im);
	}
	return f;
}

mrpt::obs::CObservation3DRangeScan::Ptr makeObservation(
	const DepthFrame& f, const mrpt::poses::CPose3D& sensorPose, const std::string& label, double timestamp,
	float maxRange)
{
	auto o = mrpt::obs::CObservation3DRangeScan::Create();
	o->sensorLabel = label;
	o->timestamp = mrpt::Clock::fromDouble(timestamp);
	o->hasRangeImage = true;
	o->rangeImage = f.range;
	o->rangeUnits = f.units;
	o->range_is_depth = true;
	o->maxRange = maxRange;
	o->sensorPose = sensorPose;
	auto& cp = o->cameraParams;
	cp.ncols = uint32_t(f.k.width);
	cp.nrows = uint32_t(f.k.height);
	cp.fx(f.k.fx);
	cp.fy(f.k.fy);
	cp.cx(f.k.cx);
	cp.cy(f.k.cy);
	cp.dist.fill(0);
	if (f.rgb)
	{
		o->hasIntensityImage = true;
		o->intensityImage = *f.rgb;
		o->intensityImageChannel = mrpt::obs::CObservation3DRangeScan::CH_VISIBLE;
		o->cameraParamsIntensity = cp;
		o->relativePoseIntensityWRTDepth = opticalInSensorFrame();  // registered: no translation
	}
	return o;
}
}  // namespace gam::import
