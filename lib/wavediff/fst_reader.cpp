// FST reader on fstapi (Debian's verilator package). fstReaderIterBlocks2 pushes value changes in
// time order through a callback; it runs in a producer thread that fills chunks of records into
// a bounded queue, and step() pulls from it. Memory: fstapi decompresses one value-change block
// at a time (its size is set by the writer: at most 128 MiB of change data for gtkwave's and
// Verilator's writers by default), plus at most kQueue + 2 chunks of kChunkRecs records here,
// plus the slots: so it grows with the number of signals and the block size, not the file length.
#include <fmt/format.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>
#include <utility>

#include "child.hpp"
#include "fst_chain.hpp"
#include "gtkwave/fstapi.h"
#include "textfile.hpp"
#include "wave_reader_impl.hpp"

namespace dpc31::wavediff {

namespace {

constexpr std::size_t kChunkRecs = 16384;
constexpr std::size_t kQueue = 4;
constexpr std::uint32_t kNone = UINT32_MAX;

struct Rec {
  std::uint64_t time;
  std::uint32_t slot;
  std::uint32_t off;
};

struct Chunk {
  std::vector<Rec> recs;
  std::vector<unsigned char> data;
};

bool is_real(unsigned char typ) {
  return typ == FST_VT_VCD_REAL || typ == FST_VT_VCD_REAL_PARAMETER || typ == FST_VT_VCD_REALTIME ||
         typ == FST_VT_SV_SHORTREAL;
}

// The value length fstapi gives each handle, from the file's geometry block (as fstReaderInit
// reads it: the last such block wins): 0 a real (8 bytes, a double), kVarLen a variable-length
// value, else the number of bits. fstapi sizes the value it passes to a callback by this, not by
// the hierarchy (finding 3 of docs/security.md).
constexpr std::uint32_t kVarLen = 0xFFFFFFFF;
using Geometry = std::vector<std::uint32_t>;  // index: handle - 1

class FstReader final : public WaveReader {
 public:
  // An empty geometry: a gzip-wrapped file.
  FstReader(const std::string& path, int fd, void* ctx, Geometry geometry)
      : fd_(fd), ctx_(ctx), geometry_(std::move(geometry)), gzip_(geometry_.empty()) {
    path_ = path;
    format_ = "fst";
    read_hierarchy();
    fstReaderIterBlocksSetNativeDoublesOnCallback(ctx_, 1);
    fill_ = std::make_unique<Chunk>();
  }
  ~FstReader() override {
    {
      std::lock_guard<std::mutex> lk(m_);
      abort_ = true;
    }
    cv_.notify_all();
    if (producer_.joinable()) producer_.join();
    fstReaderClose(ctx_);
    ::close(fd_);
  }
  FstReader(const FstReader&) = delete;
  FstReader& operator=(const FstReader&) = delete;

  bool has_next() override { return ensure(); }
  void set_limit_end(std::uint64_t t) override {
    if (!producer_.joinable()) fstReaderSetLimitTimeRange(ctx_, 0, t);
  }
  std::uint64_t next_time() override { return ensure() ? cur_->recs[idx_].time : 0; }

  const std::vector<std::uint32_t>& step() override {
    changed_.clear();
    ++stamp_;
    if (!ensure()) return changed_;
    const std::uint64_t t = cur_->recs[idx_].time;
    if (!first_ && t < time_) fail(path_, 0, "time goes backwards");
    first_ = false;
    time_ = t;
    while (ensure() && cur_->recs[idx_].time == t) {
      const Rec& r = cur_->recs[idx_];
      Slot& s = slots_[r.slot];
      const unsigned char* v = cur_->data.data() + r.off;
      if (s.real) {
        std::memcpy(&s.value, v, sizeof(double));
      } else {
        for (std::uint32_t i = 0; i < s.width; ++i) {
          const char c = value_char(static_cast<char>(v[i]));
          s.bits[i] = c != 0 ? c : 'x';
        }
      }
      touch(r.slot);
      ++idx_;
    }
    return changed_;
  }

 private:
  int fd_;  // the input, open while fstapi reads it by /proc/self/fd/N
  void* ctx_;
  Geometry geometry_;
  bool gzip_;
  std::vector<std::uint32_t> handle_slot_;  // FST handle -> slot
  std::vector<std::uint32_t> slot_bytes_;   // bytes per value record of a slot
  std::thread producer_;
  std::mutex m_;
  std::condition_variable cv_;
  std::deque<std::unique_ptr<Chunk>> queue_;
  std::vector<std::unique_ptr<Chunk>> free_;
  bool done_ = false;
  bool abort_ = false;
  std::exception_ptr error_;     // the producer's, rethrown by the consumer
  std::unique_ptr<Chunk> fill_;  // producer side
  std::unique_ptr<Chunk> cur_;   // consumer side
  std::size_t idx_ = 0;
  bool first_ = true;

  void read_hierarchy() {
    const int ts = fstReaderGetTimescale(ctx_);
    ts_pow_ = ts + 15;
    if (ts_pow_ < 0 || ts_pow_ > 17) {
      fail(path_, 0, fmt::format("timescale 1e{} s is outside 1 fs .. 100 s", ts));
    }
    const fstHandle maxh = fstReaderGetMaxHandle(ctx_);
    handle_slot_.assign(static_cast<std::size_t>(maxh) + 1, kNone);
    Declarations decl(path_);
    fstReaderSetFacProcessMaskAll(ctx_);
    std::uint64_t declared = 0;
    while (fstHier* h = fstReaderIterateHier(ctx_)) {
      if (h->htyp == FST_HT_SCOPE) {
        decl.open_scope(std::string_view(h->u.scope.name, h->u.scope.name_length), 0);
      } else if (h->htyp == FST_HT_UPSCOPE) {
        decl.close_scope();
      } else if (h->htyp == FST_HT_VAR) {
        ++declared;
        const auto& hv = h->u.var;
        if (hv.handle == 0 || hv.handle > maxh) fail(path_, 0, "variable with a bad handle");
        if (hv.length == 0 || hv.typ == FST_VT_GEN_STRING) {  // variable-length: not compared
          fstReaderClrFacProcessMask(ctx_, hv.handle);
          continue;
        }
        const bool real = is_real(hv.typ);
        // (A gzip-wrapped file, which fstapi unpacks to a file of its own, is not checked.)
        const std::uint32_t geom = hv.handle <= geometry_.size() ? geometry_[hv.handle - 1] : 0;
        if (!gzip_ && (hv.handle > geometry_.size() || (real ? geom != 0 : geom != hv.length))) {
          fail(path_, 0,
               fmt::format("not a readable FST file (corrupt: the variable '{}' has {} in the "
                           "hierarchy and {} in the geometry block)",
                           shown(std::string_view(hv.name, hv.name_length)),
                           real ? "a real" : fmt::format("{} bits", hv.length),
                           hv.handle > geometry_.size() ? "no entry"
                           : geom == 0                  ? "a real"
                           : geom == kVarLen            ? "a variable length"
                                                        : fmt::format("{} bits", geom)));
        }
        std::uint32_t slot = handle_slot_[hv.handle];
        if (slot == kNone) {
          decl.slot(real ? 64 : hv.length, 0);
          slot = static_cast<std::uint32_t>(slots_.size());
          Slot s;
          s.real = real;
          s.width = real ? 64 : hv.length;
          if (real) {
            s.value = std::numeric_limits<double>::quiet_NaN();
          } else {
            s.bits.assign(hv.length, 'x');
          }
          slots_.push_back(std::move(s));
          slot_bytes_.push_back(real ? 8 : hv.length);
          handle_slot_[hv.handle] = slot;
        }
        Var v;
        split_reference(std::string_view(hv.name, hv.name_length), v.name, v.msb, v.lsb);
        v.name = decl.name(v.name, 0);
        v.slot = slot;
        vars_.push_back(std::move(v));
      }
    }
    // A hierarchy block that does not decompress reads as fewer variables (or none): fstapi
    // does not say so.
    if (declared != fstReaderGetVarCount(ctx_)) {
      fail(path_, 0,
           fmt::format("not a readable FST file (corrupt: the hierarchy has {} of the {} "
                       "variables of the header)",
                       declared, fstReaderGetVarCount(ctx_)));
    }
  }

  static void on_change(void* self, std::uint64_t time, fstHandle h, const unsigned char* v) {
    static_cast<FstReader*>(self)->push(time, h, v);
  }
  // Only for handles the geometry declares variable-length, which the hierarchy check leaves
  // unmasked only if the hierarchy says so too: a length that is not the slot's is refused.
  static void on_change_varlen(void* self, std::uint64_t time, fstHandle h, const unsigned char* v,
                               std::uint32_t len) {
    static_cast<FstReader*>(self)->push(time, h, v, len);
  }

  // `v` holds the handle's geometry length (checked against the hierarchy's in read_hierarchy)
  // or, from the variable-length callback, `len` bytes.
  void push(std::uint64_t time, fstHandle h, const unsigned char* v, std::uint32_t len = kNone) {
    if (abort_seen_ || h >= handle_slot_.size()) return;
    const std::uint32_t slot = handle_slot_[h];
    if (slot == kNone) return;
    if (len != kNone && len != slot_bytes_[slot]) {
      fail(
          path_, 0,
          fmt::format("not a readable FST file (corrupt: a value of {} bytes for a variable of {})",
                      len, slot_bytes_[slot]));
    }
    Chunk& c = *fill_;
    const auto off = static_cast<std::uint32_t>(c.data.size());
    c.data.insert(c.data.end(), v, v + slot_bytes_[slot]);
    c.recs.push_back({time, slot, off});
    if (c.recs.size() >= kChunkRecs || c.data.size() >= (1u << 22)) hand_over();
  }

  bool abort_seen_ = false;  // producer's copy of abort_

  void hand_over() {
    std::unique_lock<std::mutex> lk(m_);
    cv_.wait(lk, [this] { return queue_.size() < kQueue || abort_; });
    if (abort_) {
      abort_seen_ = true;
      fill_->recs.clear();
      fill_->data.clear();
      return;
    }
    queue_.push_back(std::move(fill_));
    if (!free_.empty()) {
      fill_ = std::move(free_.back());
      free_.pop_back();
    } else {
      fill_ = std::make_unique<Chunk>();
    }
    lk.unlock();
    cv_.notify_all();
  }

  void produce() {
    // An exception here (std::bad_alloc; in the fuzz build fstapi's exit()) would end the
    // process from this thread: it goes to the consumer, which rethrows it from step().
    std::exception_ptr error;
    try {
      fstReaderIterBlocks2(ctx_, &FstReader::on_change, &FstReader::on_change_varlen, this,
                           nullptr);
      if (!fill_->recs.empty()) hand_over();
    } catch (...) {
      error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lk(m_);
      error_ = error;
      done_ = true;
    }
    cv_.notify_all();
  }

  // Makes cur_->recs[idx_] the next record; false when there is none.
  bool ensure() {
    if (!producer_.joinable()) producer_ = std::thread([this] { produce(); });
    while (!cur_ || idx_ >= cur_->recs.size()) {
      std::unique_lock<std::mutex> lk(m_);
      if (cur_) {
        cur_->recs.clear();
        cur_->data.clear();
        free_.push_back(std::move(cur_));
      }
      cv_.wait(lk, [this] { return !queue_.empty() || done_; });
      if (queue_.empty()) {
        if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
        return false;
      }
      cur_ = std::move(queue_.front());
      queue_.pop_front();
      idx_ = 0;
      lk.unlock();
      cv_.notify_all();
    }
    return true;
  }
};

// fstapi mallocs the sizes an LZ4 hierarchy block announces (its uncompressed length, and for
// LZ4DUO the inner length, a varint) and writes through the result unchecked: absurd sizes are
// refused before fstapi sees them (docs/robustness.md, finding 3). `f` is just past the block's
// 9-byte header.
constexpr std::uint64_t kMaxHierarchyBytes = std::uint64_t{1} << 30;

std::string check_lz4_hierarchy(std::FILE* f, std::uint64_t pos, std::uint64_t len, bool duo) {
  unsigned char b[8 + 10];
  const std::size_t n = std::fread(b, 1, sizeof b, f);  // after the 9-byte block header
  if (len < 16 + 1 || n < 8 + (duo ? 1u : 0u)) {
    return fmt::format("hierarchy block at byte {} too short", pos);
  }
  std::uint64_t uclen = 0;
  for (int i = 0; i < 8; ++i) uclen = uclen << 8 | b[i];
  std::uint64_t inner = 0;
  if (duo) {  // LEB128-style varint, as fstGetVarint64 reads it
    int shift = 0;
    std::size_t i = 8;
    for (; i < n && shift < 64; ++i, shift += 7) {
      inner |= static_cast<std::uint64_t>(b[i] & 0x7F) << shift;
      if ((b[i] & 0x80) == 0) break;
    }
    // fstapi looks for the varint's end without a bound: it must end inside the data.
    if (i == n || shift >= 64 || i - 8 + 1 > len - 16) {
      return fmt::format("hierarchy block at byte {}: bad length", pos);
    }
  }
  if (uclen > kMaxHierarchyBytes || inner > kMaxHierarchyBytes) {
    return fmt::format("hierarchy block at byte {} claims {} bytes uncompressed", pos,
                       std::max(uclen, inner));
  }
  return {};
}

}  // namespace

namespace {

void ignore_change(void*, std::uint64_t, fstHandle, const unsigned char*) {}
void ignore_varlen(void*, std::uint64_t, fstHandle, const unsigned char*, std::uint32_t) {}

// The block chain (util/outfile/fst_chain.hpp) must end exactly at the end of the file: fstapi
// reads a file cut inside its last blocks without complaint, as a shorter waveform. The LZ4
// hierarchy blocks before any break are checked for absurd sizes too.
// The geometry block: its uncompressed length and handle count (8 bytes each, big-endian), then
// one varint per handle, zlib-compressed unless the two lengths are equal. Read here with bounds
// on everything; fstapi's own reading of it trusts the lengths.
Geometry read_geometry(std::FILE* f, const std::string& path, const fst_chain::Block& b) {
  const auto corrupt = [&](const std::string& what) {
    fail(path, 0,
         fmt::format("not a readable FST file (corrupt: the geometry block at byte {} {})", b.pos,
                     what));
  };
  unsigned char head[16];
  if (b.len < 8 + 16 || std::fseek(f, static_cast<long>(b.pos + 9), SEEK_SET) != 0 ||
      std::fread(head, 1, 16, f) != 16) {
    corrupt("is too short");
  }
  std::uint64_t uclen = 0;
  std::uint64_t handles = 0;
  for (int i = 0; i < 8; ++i) uclen = uclen << 8 | head[i];
  for (int i = 8; i < 16; ++i) handles = handles << 8 | head[i];
  const std::uint64_t clen = b.len - 24;
  // At most 5 bytes a varint: a longer claim is not a geometry of this many handles; and zlib
  // packs at most about 1032 : 1, so a larger claim is not what the compressed bytes hold (the
  // buffer is sized by the claim).
  if (handles > (std::uint64_t{1} << 28) || uclen > 5 * handles || clen > uclen ||
      (clen != uclen && uclen > 1100 * clen + 64)) {
    corrupt(fmt::format("claims {} handles in {} bytes", handles, uclen));
  }
  std::vector<unsigned char> packed(clen);
  if (std::fread(packed.data(), 1, clen, f) != clen) corrupt("is cut short");
  std::vector<unsigned char> data;
  if (clen == uclen) {
    data = std::move(packed);
  } else {
    data.resize(uclen);
    uLongf got = uclen;
    if (uncompress(data.data(), &got, packed.data(), clen) != Z_OK || got != uclen) {
      corrupt("does not decompress");
    }
  }
  Geometry g;
  g.reserve(handles);
  std::size_t at = 0;
  for (std::uint64_t h = 0; h < handles; ++h) {
    std::uint32_t v = 0;
    int shift = 0;
    for (;; shift += 7) {
      if (at == data.size()) corrupt("ends inside its lengths");
      const unsigned char c = data[at++];
      if (shift < 32) v |= static_cast<std::uint32_t>(c & 0x7F) << shift;
      if ((c & 0x80) == 0) break;
    }
    g.push_back(v);
  }
  return g;
}

Geometry check_blocks(const std::string& path, const std::string& access) {
  std::FILE* f = std::fopen(access.c_str(), "rb");
  if (f == nullptr) fail(path, 0, fmt::format("cannot open: {}", std::strerror(errno)));
  const fst_chain::Chain c = fst_chain::walk(f);
  std::string problem;
  for (const fst_chain::Block& b : c.blocks) {
    if (b.type != FST_BL_HIER_LZ4 && b.type != FST_BL_HIER_LZ4DUO) continue;
    if (std::fseek(f, static_cast<long>(b.pos + 9), SEEK_SET) == 0) {
      problem = check_lz4_hierarchy(f, b.pos, b.len, b.type == FST_BL_HIER_LZ4DUO);
    }
    if (!problem.empty()) {
      problem = "corrupt: " + problem;
      break;
    }
  }
  if (problem.empty()) problem = c.problem;
  Geometry g;
  if (!c.not_fst && !c.gzip && problem.empty()) {
    const auto last = std::find_if(c.blocks.rbegin(), c.blocks.rend(),
                                   [](const fst_chain::Block& b) { return b.type == FST_BL_GEOM; });
    if (last == c.blocks.rend()) problem = "no geometry block";
    try {
      if (last != c.blocks.rend()) g = read_geometry(f, path, *last);
    } catch (...) {
      std::fclose(f);
      throw;
    }
  }
  std::fclose(f);
  if (c.not_fst) fail(path, 0, "not a readable FST file");
  if (!problem.empty()) fail(path, 0, fmt::format("not a readable FST file ({})", problem));
  return g;
}

// fstapi prints to stderr and exit()s on a block that does not decompress, and may crash on other
// corruption: the whole file is read once in a child process first (docs/bad-input.md). A file
// the child reads to the end decompresses the same way here.
void check_in_child(const std::string& path, const std::string& access) {
  constexpr int kNotFst = 3;
  const child::Result r = child::call([&access] {
    void* ctx = fstReaderOpen(access.c_str());
    if (ctx == nullptr) return kNotFst;
    fstReaderSetFacProcessMaskAll(ctx);
    while (fstReaderIterateHier(ctx) != nullptr) {
    }
    fstReaderIterBlocks2(ctx, ignore_change, ignore_varlen, nullptr, nullptr);
    fstReaderClose(ctx);
    return 0;
  });
  if (r.exit_code == 0) return;
  if (r.exit_code == kNotFst) fail(path, 0, "not a readable FST file");
  fail(path, 0,
       fmt::format("not a readable FST file (corrupt or truncated: its reader {})",
                   r.exit_code >= 0 ? fmt::format("exited with {}", r.exit_code) : r.error));
}

}  // namespace

std::unique_ptr<WaveReader> open_fst(const std::string& path, int fd, const std::string& access) {
  void* ctx = nullptr;
  try {
    Geometry geometry = check_blocks(path, access);
    check_in_child(path, access);
    ctx = fstReaderOpen(access.c_str());
    if (ctx == nullptr) fail(path, 0, "not a readable FST file");
    return std::make_unique<FstReader>(path, fd, ctx, std::move(geometry));
  } catch (...) {
    // Failed before the reader owned them (in the hierarchy, or earlier).
    if (ctx != nullptr) fstReaderClose(ctx);
    ::close(fd);
    throw;
  }
}

}  // namespace dpc31::wavediff
