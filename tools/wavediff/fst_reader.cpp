// FST reader on fstapi (Debian's verilator package). fstReaderIterBlocks2 pushes value changes in
// time order through a callback; it runs in a producer thread that fills chunks of records into
// a bounded queue, and step() pulls from it. Memory: fstapi decompresses one value-change block
// at a time (its size is set by the writer: at most 128 MiB of change data for gtkwave's and
// Verilator's writers by default), plus at most kQueue + 2 chunks of kChunkRecs records here,
// plus the slots: so it grows with the number of signals and the block size, not the file length.
#include <fmt/format.h>

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>
#include <utility>

#include "gtkwave/fstapi.h"
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

class FstReader final : public WaveReader {
 public:
  FstReader(const std::string& path, void* ctx) : ctx_(ctx) {
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
  void* ctx_;
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
    std::vector<std::string> scopes;
    fstReaderSetFacProcessMaskAll(ctx_);
    while (fstHier* h = fstReaderIterateHier(ctx_)) {
      if (h->htyp == FST_HT_SCOPE) {
        scopes.emplace_back(h->u.scope.name, h->u.scope.name_length);
      } else if (h->htyp == FST_HT_UPSCOPE) {
        if (!scopes.empty()) scopes.pop_back();
      } else if (h->htyp == FST_HT_VAR) {
        const auto& hv = h->u.var;
        if (hv.handle == 0 || hv.handle > maxh) fail(path_, 0, "variable with a bad handle");
        if (hv.length == 0 || hv.typ == FST_VT_GEN_STRING) {  // variable-length: not compared
          fstReaderClrFacProcessMask(ctx_, hv.handle);
          continue;
        }
        const bool real = is_real(hv.typ);
        std::uint32_t slot = handle_slot_[hv.handle];
        if (slot == kNone) {
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
        std::string full;
        for (const auto& s : scopes) full += s + ".";
        v.name = full + v.name;
        v.slot = slot;
        vars_.push_back(std::move(v));
      }
    }
  }

  static void on_change(void* self, std::uint64_t time, fstHandle h, const unsigned char* v) {
    static_cast<FstReader*>(self)->push(time, h, v);
  }
  static void on_change_varlen(void* self, std::uint64_t time, fstHandle h, const unsigned char* v,
                               std::uint32_t /*len*/) {
    static_cast<FstReader*>(self)->push(time, h, v);
  }

  void push(std::uint64_t time, fstHandle h, const unsigned char* v) {
    if (abort_seen_ || h >= handle_slot_.size()) return;
    const std::uint32_t slot = handle_slot_[h];
    if (slot == kNone) return;
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

// fstapi walks the file block by block (a type byte, a 64-bit big-endian length, the body), at
// the next block = here + 1 + length, with no check: a length that wraps the position around
// makes it read the same blocks forever, and a header cut off by the end of the file is read
// from uninitialised memory. Such files are refused before fstapi sees them (docs/robustness.md).
// The same for the sizes of LZ4 hierarchy blocks (below). A gzip-wrapped FST (type 254) is
// unpacked by fstapi first; its inner blocks are not checked here.
constexpr std::uint64_t kMaxHierarchyBytes = std::uint64_t{1} << 30;

std::string check_lz4_hierarchy(std::FILE* f, std::uint64_t pos, std::uint64_t len,
                                std::uint64_t file_size, bool duo) {
  unsigned char b[8 + 10];
  const std::size_t n = std::fread(b, 1, sizeof b, f);  // after the 9-byte block header
  if (len < 16 + 1 || n < 8 + (duo ? 1u : 0u)) {
    return fmt::format("hierarchy block at byte {} too short", pos);
  }
  // Its compressed size (len - 16) is malloc'd and read as well: the block must be in the file.
  if (len > file_size - pos - 1) {
    return fmt::format("hierarchy block at byte {} runs past the end of the file", pos);
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

void check_block_chain(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return;  // fstReaderOpen reports it
  std::uint64_t size = 0;
  if (fseeko(f, 0, SEEK_END) == 0) size = static_cast<std::uint64_t>(ftello(f));
  std::uint64_t pos = 0;
  std::string error;
  for (;;) {
    if (fseeko(f, static_cast<off_t>(pos), SEEK_SET) != 0) break;
    unsigned char h[9];
    const std::size_t n = std::fread(h, 1, sizeof h, f);
    if (n == 0 || (pos == 0 && h[0] == FST_BL_ZWRAPPER)) break;
    if (n < sizeof h) {
      if (pos == 0) break;  // not an FST at all: fstReaderOpen says so
      error = fmt::format("block header at byte {} cut off by the end of the file", pos);
      break;
    }
    std::uint64_t len = 0;
    for (int i = 1; i < 9; ++i) len = len << 8 | h[i];
    if (h[0] == FST_BL_HIER_LZ4 || h[0] == FST_BL_HIER_LZ4DUO) {
      // fstapi mallocs the sizes of an LZ4 hierarchy block as given (uncompressed length, and
      // for LZ4DUO the inner length, a varint) and writes through the result unchecked.
      error = check_lz4_hierarchy(f, pos, len, size, h[0] == FST_BL_HIER_LZ4DUO);
      if (!error.empty()) break;
    }
    const std::uint64_t next = pos + 1 + len;
    if (next <= pos) {
      error =
          fmt::format("block at byte {} has a length of {} (the chain runs backwards)", pos, len);
      break;
    }
    pos = next;
  }
  std::fclose(f);
  if (!error.empty()) fail(path, 0, "corrupt FST: " + error);
}

}  // namespace

std::unique_ptr<WaveReader> open_fst(const std::string& path) {
  check_block_chain(path);
  void* ctx = fstReaderOpen(path.c_str());
  if (ctx == nullptr) fail(path, 0, "not a readable FST file");
  try {
    return std::make_unique<FstReader>(path, ctx);
  } catch (...) {
    fstReaderClose(ctx);  // the constructor failed in the hierarchy, before owning the context
    throw;
  }
}

}  // namespace dpc31::wavediff
