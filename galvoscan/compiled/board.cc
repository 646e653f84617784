// The simulated board around the compiled system top: a host UART (8N1), the machine's
// interlock loop and laser alarms, a scan head on the XY2-100 wires and a laser on the DB25
// pins, with the records galvoscan's Python board keeps (galvoscan/sim/board.py).
//
// Time is kept in integer femtoseconds, as Amaranth's simulator keeps it, and every process
// wakes at the instants its Python twin wakes, so both backends give the same records to the
// clock: the clock toggles every `half_fs` from `half_fs` on (Amaranth's add_clock); at an
// instant that holds a clock edge and a process's wake, the edge comes first and the process
// sees the design settled after it; a run to a deadline does what falls before it and leaves
// what falls on it for the next run (Simulator.run_until). Python calls in once per run, never
// once per clock, and takes the records in batches.
//
// The design is the header and source Yosys' write_cxxrtl makes of the top (TOP_HEADER); the
// ports that differ between builds come in as macros (GS_ALARM_BITS: the laser alarm inputs).

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <deque>
#include <new>
#include <vector>

#include TOP_HEADER

namespace {

using design_t = cxxrtl_design::p_top;

// What a run ended on.
enum Outcome : int { RAN = 0, PROTOCOL_ERROR = 1 };

// The recorded laser pins, one bit each in this order (galvoscan.sim.board.LASER_PINS).
enum LaserPin { ENABLE, MO, AM, PRR, LATCH, GUIDE };

struct XY2Receiver {
    // The scan head's decoder (galvoscan/sim/xy2_receiver.py): bits sampled on each falling
    // xy2_clk edge, a frame from SYNC's rise to the bit with SYNC low (the parity bit).
    bool started = false;       // a SYNC rise has been seen
    int count = 0;
    bool last_sync = false;
    uint32_t word_x = 0, word_y = 0;

    // 1: a frame is complete (x, y set); 0: not yet; -1: a protocol error (message set).
    int sample(bool sync, bool x, bool y, int32_t &out_x, int32_t &out_y, char *message,
               size_t size) {
        if (sync && !last_sync) {
            if (started && count) {
                snprintf(message, size, "SYNC rose after %d bits, mid-frame", count);
                return -1;
            }
            started = true;
            word_x = word_y = 0;
            count = 0;
        }
        last_sync = sync;
        if (!started)
            return 0;
        if (!sync && count == 0) {
            snprintf(message, size, "a clock with SYNC low between frames: frames must be "
                                    "back to back");
            return -1;
        }
        word_x = (word_x << 1) | x;
        word_y = (word_y << 1) | y;
        count++;
        if (sync) {
            if (count >= 20) {
                snprintf(message, size, "SYNC high for 20 bits: the parity bit is missing");
                return -1;
            }
            return 0;
        }
        if (count != 20) {
            snprintf(message, size, "SYNC fell after %d bits, not 19", count - 1);
            return -1;
        }
        count = 0;
        if (!check(word_x, "X", out_x, message, size) ||
                !check(word_y, "Y", out_y, message, size))
            return -1;
        return 1;
    }

    static bool check(uint32_t word, const char *axis, int32_t &out, char *message,
                      size_t size) {
        word &= 0xFFFFF;
        if (__builtin_popcount(word) % 2) {
            snprintf(message, size, "%s frame %05x has odd parity", axis, word);
            return false;
        }
        if ((word >> 17) != 0b001) {
            unsigned control = word >> 17;
            snprintf(message, size, "%s frame %05x has control bits %u%u%u, not 001", axis,
                     word, (control >> 2) & 1, (control >> 1) & 1, control & 1);
            return false;
        }
        out = (word >> 1) & 0xFFFF;
        return true;
    }
};

struct Board {
    design_t top;

    // Timing, in femtoseconds (from Python, rounded as Amaranth rounds its delays).
    int64_t half_fs;            // half a clock period
    int64_t bit_fs;             // one UART bit
    int64_t bit_and_half_fs;    // a bit and a half: the first data bit's middle
    int64_t machine_fs;         // how often the interlock and alarm pins are set

    int64_t next_toggle;        // the clock's next edge
    bool clk = false;
    int64_t cycles = 0;         // rising edges so far (the Python board's Timed.cycles)

    // The host's transmitter: a byte 8N1 on uart_rx, back to back, woken every bit.
    std::deque<uint8_t> to_board;
    int64_t bytes_started = 0;
    int64_t tx_wake = 0;
    int tx_level_index = -1;    // -1: idle; 0 start bit, 1..8 data, 9 stop; 10: byte done
    uint8_t tx_byte = 0;

    // The host's receiver: a start bit's falling edge, then each bit in its middle.
    bool rx_sampling = false;
    int64_t rx_wake = 0;
    int rx_bit = 0;
    unsigned rx_value = 0;
    int64_t framing_errors = 0;

    // The machine: interlock loop and laser alarms, set every machine_fs from t = 0.
    int64_t machine_wake = 0;
    bool interlock_closed = true, alarms_clear = true;

    // Pins as last seen, for their edges.
    bool last_tx = true, last_xy2_clk = false, last_sync = false, last_prr = false;
    uint32_t last_laser = 0;

    XY2Receiver receiver;
    char message[256] = {0};

    // The records, taken by Python in batches.
    std::vector<int64_t> frames;        // cycle, x, y
    std::vector<int64_t> sync_rises;    // cycle
    std::vector<int64_t> pulses;        // cycle
    std::vector<int64_t> laser_changes; // cycle, pins (LaserPin bits)
    std::vector<int64_t> bytes_in;      // cycle, byte
    std::vector<int64_t> bytes_out;     // byte

    uint32_t laser_pins() const {
        return (uint32_t(top.p_laser__enable.get<bool>()) << ENABLE) |
               (uint32_t(top.p_laser__mo.get<bool>()) << MO) |
               (uint32_t(top.p_laser__am.get<bool>()) << AM) |
               (uint32_t(top.p_laser__prr.get<bool>()) << PRR) |
               (uint32_t(top.p_laser__latch.get<bool>()) << LATCH) |
               (uint32_t(top.p_laser__guide.get<bool>()) << GUIDE);
    }

    // Evaluate until nothing changes. (CXXRTL's step() stops after the commit that follows
    // a converged eval, so the outputs it leaves are those from before a clock edge's commit;
    // the eval after that commit brings them up to the new state.)
    void settle() {
        do
            top.eval();
        while (top.commit());
    }

    // After the design has settled: the edges and changes the Python board's triggers see.
    // Returns false on a protocol error.
    bool watch_pins() {
        bool tx = top.p_uart__tx.get<bool>();
        if (last_tx && !tx && !rx_sampling) {
            rx_sampling = true;
            rx_bit = 0;
            rx_value = 0;
            rx_wake = now + bit_and_half_fs;
        }
        last_tx = tx;
        bool xy2_clk = top.p_xy2__clk.get<bool>();
        bool sync = top.p_xy2__sync.get<bool>();
        bool ok = true;
        if (last_xy2_clk && !xy2_clk) {
            int32_t x = 0, y = 0;
            int got = receiver.sample(sync, top.p_xy2__x.get<bool>(), top.p_xy2__y.get<bool>(),
                                      x, y, message, sizeof message);
            if (got < 0)
                ok = false;
            else if (got > 0) {
                frames.push_back(cycles);
                frames.push_back(x);
                frames.push_back(y);
            }
        }
        last_xy2_clk = xy2_clk;
        if (sync && !last_sync)
            sync_rises.push_back(cycles);
        last_sync = sync;
        bool prr = top.p_laser__prr.get<bool>();
        if (prr && !last_prr && top.p_laser__am.get<bool>())
            pulses.push_back(cycles);
        last_prr = prr;
        uint32_t laser = laser_pins();
        if (laser != last_laser) {
            laser_changes.push_back(cycles);
            laser_changes.push_back(laser);
            last_laser = laser;
        }
        return ok;
    }

    int64_t now = 0;

    void set_machine_pins() {
        top.p_interlock__open.set<bool>(!interlock_closed);
#if GS_ALARM_BITS > 0
        top.p_laser__alarm.set<uint32_t>(alarms_clear ? 0u : (1u << GS_ALARM_BITS) - 1);
#endif
    }

    void host_transmitter() {
        if (tx_level_index >= 0) {
            tx_level_index++;
            if (tx_level_index == 10) {         // the stop bit's time is over
                bytes_in.push_back(cycles);
                bytes_in.push_back(tx_byte);
                tx_level_index = -1;
            } else {
                bool level = tx_level_index <= 8 ? (tx_byte >> (tx_level_index - 1)) & 1
                                                 : true;
                top.p_uart__rx.set<bool>(level);
            }
        }
        if (tx_level_index < 0 && !to_board.empty()) {
            tx_byte = to_board.front();
            to_board.pop_front();
            bytes_started++;
            tx_level_index = 0;
            top.p_uart__rx.set<bool>(false);
        }
        tx_wake += bit_fs;
    }

    void host_receiver() {
        bool tx = top.p_uart__tx.get<bool>();
        if (rx_bit < 8) {
            rx_value |= unsigned(tx) << rx_bit;
            rx_bit++;
            rx_wake += bit_fs;
            return;
        }
        if (tx)
            bytes_out.push_back(rx_value);
        else
            framing_errors++;
        rx_sampling = false;
    }

    // Run every event before `deadline`; leave those on it for the next run.
    int run_until(int64_t deadline) {
        while (true) {
            int64_t t = next_toggle;
            if (tx_wake < t) t = tx_wake;
            if (rx_sampling && rx_wake < t) t = rx_wake;
            if (machine_wake < t) t = machine_wake;
            if (t >= deadline)
                break;
            now = t;
            if (next_toggle == t) {
                clk = !clk;
                top.p_clk.set<bool>(clk);
                next_toggle += half_fs;
                if (clk) {
                    settle();
                    cycles++;
                    if (!watch_pins())
                        return PROTOCOL_ERROR;
                } else {
                    // Nothing in the design acts on the falling edge: only note it, so the
                    // next rising one is seen as an edge.
                    top.prev_p_clk = top.p_clk;
                }
            }
            // Then the host's and the machine's processes woken at this instant, in the order
            // the Python board added them: each input it sets settles the design at once.
            bool changed = false;
            if (tx_wake == t) {
                host_transmitter();
                changed = true;
            }
            if (rx_sampling && rx_wake == t)
                host_receiver();
            if (machine_wake == t) {
                set_machine_pins();
                machine_wake += machine_fs;
                changed = true;
            }
            if (changed) {
                settle();
                if (!watch_pins())
                    return PROTOCOL_ERROR;
            }
        }
        now = deadline;
        return RAN;
    }
};

}  // namespace

extern "C" {

// timing: the clock's first edge, half a clock, a UART bit, a bit and a half, the machine's
// period (all fs).
void *gs_board_new(const int64_t *timing) {
    Board *board = new (std::nothrow) Board();
    if (board == nullptr)
        return nullptr;
    board->next_toggle = timing[0];
    board->half_fs = timing[1];
    board->bit_fs = timing[2];
    board->bit_and_half_fs = timing[3];
    board->machine_fs = timing[4];
    // The ports' initial values (Amaranth's port inits are not in the netlist): the host's
    // UART idles high, the SPI link is deselected, the interlock and alarm pins as the
    // machine has them from the first instant.
    board->top.p_uart__rx.set<bool>(true);
    board->top.p_spi__cs__n.set<bool>(true);
    board->top.p_spi__sck.set<bool>(false);
    board->top.p_spi__copi.set<bool>(false);
    board->top.p_rst.set<bool>(false);
    board->top.p_clk.set<bool>(false);
    board->settle();
    board->last_tx = board->top.p_uart__tx.get<bool>();
    board->last_laser = board->laser_pins();
    // The Python board's recorder sees the pins once as the design first settles.
    board->laser_changes.push_back(0);
    board->laser_changes.push_back(board->last_laser);
    return board;
}

void gs_board_free(void *board) { delete static_cast<Board *>(board); }

void gs_board_send(void *handle, const uint8_t *data, int64_t size) {
    Board *board = static_cast<Board *>(handle);
    board->to_board.insert(board->to_board.end(), data, data + size);
}

void gs_board_machine(void *handle, int interlock_closed, int alarms_clear) {
    Board *board = static_cast<Board *>(handle);
    board->interlock_closed = interlock_closed;
    board->alarms_clear = alarms_clear;
}

int gs_board_run_until(void *handle, int64_t deadline_fs) {
    return static_cast<Board *>(handle)->run_until(deadline_fs);
}

const char *gs_board_message(void *handle) { return static_cast<Board *>(handle)->message; }

// 0 bytes started, 1 framing errors, 2 rising clock edges, 3 the board's time (fs).
int64_t gs_board_counter(void *handle, int which) {
    Board *board = static_cast<Board *>(handle);
    switch (which) {
    case 0: return board->bytes_started;
    case 1: return board->framing_errors;
    case 2: return board->cycles;
    case 3: return board->now;
    }
    return -1;
}

// Record `which` (0 frames, 1 sync rises, 2 pulses, 3 laser changes, 4 bytes in, 5 bytes
// out): copy up to `capacity` values into `out`, drop them from the board, return how many.
int64_t gs_board_take(void *handle, int which, int64_t *out, int64_t capacity) {
    Board *board = static_cast<Board *>(handle);
    std::vector<int64_t> *records[] = {&board->frames, &board->sync_rises, &board->pulses,
                                       &board->laser_changes, &board->bytes_in,
                                       &board->bytes_out};
    if (which < 0 || which > 5)
        return -1;
    std::vector<int64_t> &record = *records[which];
    int64_t n = int64_t(record.size()) < capacity ? int64_t(record.size()) : capacity;
    if (n > 0) {
        std::memcpy(out, record.data(), size_t(n) * sizeof(int64_t));
        record.erase(record.begin(), record.begin() + n);
    }
    return n;
}

int64_t gs_board_pending(void *handle, int which) {
    Board *board = static_cast<Board *>(handle);
    std::vector<int64_t> *records[] = {&board->frames, &board->sync_rises, &board->pulses,
                                       &board->laser_changes, &board->bytes_in,
                                       &board->bytes_out};
    if (which < 0 || which > 5)
        return -1;
    return int64_t(records[which]->size());
}

}  // extern "C"
