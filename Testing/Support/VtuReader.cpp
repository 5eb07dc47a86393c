// SPDX-License-Identifier: BSD-3-Clause
#include "Support/VtuReader.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <zlib.h>

namespace faceplan::bench {

namespace {

std::string Attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const size_t p = tag.find(key);
  if (p == std::string::npos)
    return "";
  const size_t b = p + key.size(), e = tag.find('"', b);
  return tag.substr(b, e - b);
}

int Base64Value(char c) {
  if (c >= 'A' && c <= 'Z')
    return c - 'A';
  if (c >= 'a' && c <= 'z')
    return c - 'a' + 26;
  if (c >= '0' && c <= '9')
    return c - '0' + 52;
  if (c == '+')
    return 62;
  if (c == '/')
    return 63;
  return -1;
}

// Decodes base64 text (whitespace skipped) from position `pos`, stopping after `bytes` bytes
// (or at the end); advances `pos` past the consumed groups including their padding.
std::vector<unsigned char> Base64Decode(const std::string& text, size_t& pos, size_t bytes) {
  std::vector<unsigned char> out;
  int group[4], filled = 0;
  while (pos < text.size() && out.size() < bytes) {
    const char c = text[pos++];
    if (c == '=') {
      group[filled++] = 0;
    } else {
      const int v = Base64Value(c);
      if (v < 0)
        continue;
      group[filled++] = v;
    }
    if (filled == 4) {
      const unsigned char b[3] = {
          static_cast<unsigned char>((group[0] << 2) | (group[1] >> 4)),
          static_cast<unsigned char>(((group[1] & 15) << 4) | (group[2] >> 2)),
          static_cast<unsigned char>(((group[2] & 3) << 6) | group[3])};
      for (int k = 0; k < 3 && out.size() < bytes; ++k)
        out.push_back(b[k]);
      filled = 0;
    }
  }
  return out;
}

size_t TypeSize(const std::string& type) {
  if (type == "Int8" || type == "UInt8")
    return 1;
  if (type == "Int16" || type == "UInt16")
    return 2;
  if (type == "Int32" || type == "UInt32" || type == "Float32")
    return 4;
  if (type == "Int64" || type == "UInt64" || type == "Float64")
    return 8;
  return 0;
}

double ValueAt(const unsigned char* p, const std::string& type) {
  auto get = [p](auto v) {
    std::memcpy(&v, p, sizeof v);
    return static_cast<double>(v);
  };
  if (type == "Int8")
    return get(std::int8_t{});
  if (type == "UInt8")
    return get(std::uint8_t{});
  if (type == "Int16")
    return get(std::int16_t{});
  if (type == "UInt16")
    return get(std::uint16_t{});
  if (type == "Int32")
    return get(std::int32_t{});
  if (type == "UInt32")
    return get(std::uint32_t{});
  if (type == "Int64")
    return get(std::int64_t{});
  if (type == "UInt64")
    return get(std::uint64_t{});
  if (type == "Float32")
    return get(float{});
  return get(double{});
}

struct FileInfo {
  size_t headerSize = 4; // UInt32 or UInt64
  bool zlib = false;
};

std::uint64_t HeaderWord(const std::vector<unsigned char>& bytes, size_t index, size_t size) {
  if (size == 8) {
    std::uint64_t v;
    std::memcpy(&v, bytes.data() + index * 8, 8);
    return v;
  }
  std::uint32_t v;
  std::memcpy(&v, bytes.data() + index * 4, 4);
  return v;
}

bool DecodeBinary(const std::string& text, const FileInfo& info, std::vector<unsigned char>& raw,
                  std::string& error) {
  size_t pos = 0;
  const size_t h = info.headerSize;
  if (!info.zlib) {
    // Raw: a base64 header holding the byte count, then the base64 of the data.
    const std::vector<unsigned char> header = Base64Decode(text, pos, h);
    if (header.size() < h)
      return error = "truncated binary header", false;
    const size_t length = HeaderWord(header, 0, h);
    raw = Base64Decode(text, pos, length);
    if (raw.size() < length)
      return error = "truncated binary data", false;
    return true;
  }
  // Compressed: a base64 header [blocks, blockSize, lastBlockSize, compressed sizes...], then the
  // base64 of the concatenated compressed blocks.
  std::vector<unsigned char> first = Base64Decode(text, pos, 3 * h);
  if (first.size() < 3 * h)
    return error = "truncated compression header", false;
  const std::uint64_t blocks = HeaderWord(first, 0, h);
  const size_t headerBytes = (3 + blocks) * h;
  pos = 0;
  const std::vector<unsigned char> header = Base64Decode(text, pos, headerBytes);
  // Skip the header's padding: pos already stands after the last full group it used.
  if (header.size() < headerBytes)
    return error = "truncated compression header", false;
  const std::uint64_t blockSize = HeaderWord(header, 1, h), lastSize = HeaderWord(header, 2, h);
  std::uint64_t compressedTotal = 0;
  for (std::uint64_t b = 0; b < blocks; ++b)
    compressedTotal += HeaderWord(header, 3 + b, h);
  const std::vector<unsigned char> data = Base64Decode(text, pos, compressedTotal);
  if (data.size() < compressedTotal)
    return error = "truncated compressed data", false;
  raw.clear();
  size_t offset = 0;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t c = HeaderWord(header, 3 + b, h);
    uLongf size = static_cast<uLongf>((b + 1 == blocks && lastSize != 0) ? lastSize : blockSize);
    const size_t at = raw.size();
    raw.resize(at + size);
    if (uncompress(raw.data() + at, &size, data.data() + offset, static_cast<uLong>(c)) != Z_OK)
      return error = "zlib could not uncompress a block", false;
    raw.resize(at + size);
    offset += c;
  }
  return true;
}

struct Array {
  std::string name;
  int components = 1;
  std::vector<double> values;
};

bool ReadArrays(const std::string& xml, const std::string& section, const FileInfo& info,
                std::vector<Array>& arrays, std::string& error) {
  const size_t begin = xml.find("<" + section);
  if (begin == std::string::npos)
    return true; // absent section
  const size_t end = xml.find("</" + section + ">", begin);
  if (end == std::string::npos)
    return true; // empty section written as <Section/>
  size_t pos = begin;
  while (true) {
    const size_t tagStart = xml.find("<DataArray", pos);
    if (tagStart == std::string::npos || tagStart > end)
      break;
    const size_t tagEnd = xml.find('>', tagStart);
    const std::string tag = xml.substr(tagStart, tagEnd - tagStart + 1);
    const size_t close = xml.find("</DataArray>", tagEnd);
    const std::string body = xml.substr(tagEnd + 1, close - tagEnd - 1);
    pos = close + 12;
    Array array;
    array.name = Attribute(tag, "Name");
    const std::string type = Attribute(tag, "type"), format = Attribute(tag, "format");
    const std::string comps = Attribute(tag, "NumberOfComponents");
    if (!comps.empty())
      array.components = std::stoi(comps);
    if (format == "ascii") {
      std::istringstream in(body);
      double v;
      while (in >> v)
        array.values.push_back(v);
    } else if (format == "binary") {
      const size_t size = TypeSize(type);
      if (size == 0)
        return error = "unsupported data type " + type, false;
      std::vector<unsigned char> raw;
      if (!DecodeBinary(body, info, raw, error))
        return error = array.name + ": " + error, false;
      array.values.resize(raw.size() / size);
      for (size_t k = 0; k < array.values.size(); ++k)
        array.values[k] = ValueAt(raw.data() + k * size, type);
    } else {
      return error = "unsupported DataArray format '" + format + "' (appended data is not read)",
             false;
    }
    arrays.push_back(std::move(array));
  }
  return true;
}

} // namespace

bool ReadVtuTets(const std::string& path, VtuMesh& out, std::string& error) {
  std::ifstream file(path, std::ios::binary);
  if (!file)
    return error = "cannot open " + path, false;
  std::stringstream buffer;
  buffer << file.rdbuf();
  const std::string xml = buffer.str();
  const size_t vtkStart = xml.find("<VTKFile");
  if (vtkStart == std::string::npos)
    return error = path + " is not a VTK XML file", false;
  const std::string vtkTag = xml.substr(vtkStart, xml.find('>', vtkStart) - vtkStart + 1);
  if (Attribute(vtkTag, "type") != "UnstructuredGrid")
    return error = path + " is not an UnstructuredGrid", false;
  if (Attribute(vtkTag, "byte_order") == "BigEndian")
    return error = "big-endian files are not supported", false;
  FileInfo info;
  info.headerSize = Attribute(vtkTag, "header_type") == "UInt64" ? 8 : 4;
  const std::string compressor = Attribute(vtkTag, "compressor");
  if (!compressor.empty() && compressor != "vtkZLibDataCompressor")
    return error = "unsupported compressor " + compressor, false;
  info.zlib = !compressor.empty();
  if (xml.find("<AppendedData") != std::string::npos)
    return error = "appended data is not supported", false;

  std::vector<Array> points, cells, pointData;
  if (!ReadArrays(xml, "Points", info, points, error) ||
      !ReadArrays(xml, "Cells", info, cells, error) ||
      !ReadArrays(xml, "PointData", info, pointData, error))
    return error = path + ": " + error, false;
  if (points.empty() || points[0].components != 3)
    return error = path + ": no 3-component points", false;
  const std::vector<double>* connectivity = nullptr;
  const std::vector<double>* offsets = nullptr;
  const std::vector<double>* types = nullptr;
  for (const Array& a : cells) {
    if (a.name == "connectivity")
      connectivity = &a.values;
    if (a.name == "offsets")
      offsets = &a.values;
    if (a.name == "types")
      types = &a.values;
  }
  if (!connectivity || !offsets || !types)
    return error = path + ": incomplete Cells", false;
  const Eigen::Index n = static_cast<Eigen::Index>(points[0].values.size() / 3);
  out.mesh.points.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      out.mesh.points(i, c) = points[0].values[3 * i + c];
  const Eigen::Index m = static_cast<Eigen::Index>(types->size());
  out.mesh.tets.resize(m, 4);
  double previous = 0;
  for (Eigen::Index e = 0; e < m; ++e) {
    if ((*types)[e] != 10 || (*offsets)[e] - previous != 4)
      return error = path + ": a cell is not a VTK_TETRA", false;
    for (int k = 0; k < 4; ++k) {
      const double id = (*connectivity)[static_cast<size_t>(previous) + k];
      if (id < 0 || id >= n)
        return error = path + ": a cell refers to a missing point", false;
      out.mesh.tets(e, k) = static_cast<int>(id);
    }
    previous = (*offsets)[e];
  }
  out.pointData.clear();
  for (Array& a : pointData) {
    if (a.values.size() != static_cast<size_t>(n) * a.components)
      continue;
    std::vector<double> first(n);
    for (Eigen::Index i = 0; i < n; ++i)
      first[i] = a.values[i * a.components];
    out.pointData[a.name] = std::move(first);
  }
  return true;
}

} // namespace faceplan::bench
