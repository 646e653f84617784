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
// The design is the header and source Yosys' write_cxxrtl makes of the top (TOP_HEADER); its
// ports' names, and what differs between builds (GS_ALARM_BITS: the laser alarm inputs),
// come in as macros (ports.h), so that another design with these pins (a build's netlist)
// can stand in it.
//
// Besides the records every board keeps, a board can record (flags at gs_board_new) the
// scan head's raw samples and the pins on every clock, for the tests' own decoders; and its
// host can clock SPI frames into the SPI target as the UART's bytes go in.

#include <cstdint>
#include <cstdio>
#include <csignal>
#include <cstring>
#include <deque>
#include <unistd.h>
#include <new>
#include <vector>

#include TOP_HEADER
// The design's port names (GS_PORT_xy2_clk …, GS_PREV_CLK), GS_ALARM_BITS and
// GS_SETTLE_FALLING, written for each design by galvoscan/sim/compiled/model.py.
#include "ports.h"

namespace {

using design_t = cxxrtl_design::p_top;

// What a run ended on.
enum Outcome : int { RAN = 0, PROTOCOL_ERROR = 1 };

// The recorded laser pins, one bit each in this order (galvoscan.sim.board.LASER_PINS).
enum LaserPin { ENABLE, MO, AM, PRR, LATCH, GUIDE };

// The records (gs_board_take).
enum Record { FRAMES, SYNC_RISES, PULSES, LASER_CHANGES, BYTES_IN, BYTES_OUT, XY2_SAMPLES,
              PIN_CHANGES, SPI_RESULTS, Z_FRAMES, IO_CHANGES, RECORDS };

// Flags of gs_board_new.
enum Flag { RECORD_SAMPLES = 1, RECORD_PINS = 2 };

// What the host's transmitter queue holds besides bytes: a byte with a bad stop bit
// (BAD_STOP | byte), and pauses (the negated pause in fs).
const int64_t BAD_STOP = 0x100;

// The SPI host's results: a CIPO bit, or the end of a transfer.
const int64_t SPI_DONE = 2;

struct SPITransfer {
    std::vector<uint8_t> bits;
    int64_t half_fs, phase_fs;
};

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

#if GS_PLAYER
// The board's configuration flash, a W25Q128JV, from its datasheet as the FPGA reads it
// (galvoscan/sim/spi_flash.py is the Python board's, for reads and writes alike): deep
// power-down and its release (0xB9, 0xAB, tDP = tRES1 = 3 µs; any other instruction in
// power-down, or within tRES1 of the release, is ignored and counted), Read Data (0x03),
// Fast Read (0x0B), the JEDEC id (0x9F) and the status register (0x05, never busy: nothing
// here programs it). SPI mode 0: COPI taken as SCK rises, CIPO set as it falls; a read past
// the top wraps to 0; CIPO reads 1 (the pull-up) while /CS is high.
struct FlashModel {
    static const int64_t BYTES = 16 * 1024 * 1024;
    static const int64_t T_RES1_FS = 3000000000;        // 3 µs
    std::vector<uint8_t> memory = std::vector<uint8_t>(BYTES, 0xFF);
    bool powered_down = true;
    int64_t ready_at = 0;
    bool selected = false, accepted = false, last_sck = false, cipo = true;
    int n = 0, bit = 0;
    uint8_t command = 0, in = 0, out = 0xFF, next_out = 0xFF;
    uint32_t address = 0;
    int64_t commands = 0, ignored = 0;

    void byte(uint8_t value, int64_t now) {
        n++;
        if (n == 1) {
            command = value;
            address = 0;
            accepted = powered_down ? command == 0xAB : now >= ready_at;
            (accepted ? commands : ignored)++;
        } else if (n <= 4) {
            address = (address << 8) | value;
        }
        uint8_t result = 0xFF;
        if (accepted) {
            static const uint8_t jedec[3] = {0xEF, 0x40, 0x18};
            if (command == 0x03 || command == 0x0B) {
                int first = command == 0x03 ? 4 : 5;
                if (n >= first)
                    result = memory[(int64_t(address) + n - first) % BYTES];
            } else if (command == 0x9F) {
                result = n <= 3 ? jedec[n - 1] : 0xFF;
            } else if (command == 0x05) {
                result = 0;
            } else if (command == 0xAB && n >= 4) {
                result = 0x17;
            }
        }
        next_out = result;
    }

    void deselect(int64_t now) {
        selected = false;
        if (n == 0)
            return;
        if (powered_down) {
            if (command == 0xAB) {
                powered_down = false;
                ready_at = now + T_RES1_FS;
            }
            return;
        }
        if (accepted && command == 0xB9 && n == 1) {
            powered_down = true;
            ready_at = now + T_RES1_FS;
        }
    }

    bool pins(bool cs_n, bool sck, bool copi, int64_t now) {
        if (cs_n) {
            if (selected)
                deselect(now);
            last_sck = sck;
            cipo = true;
            return cipo;
        }
        if (!selected) {
            selected = true;
            n = 0;
            bit = 0;
            in = 0;
            out = next_out = 0xFF;
            cipo = true;
        }
        if (sck && !last_sck) {
            in = uint8_t((in << 1) | copi);
            if (++bit == 8) {
                bit = 0;
                byte(in, now);
            }
        } else if (last_sck && !sck) {
            if (bit == 0)
                out = next_out;
            cipo = (out >> (7 - bit)) & 1;
        }
        last_sck = sck;
        return cipo;
    }
};
#endif

struct Board {
    design_t top;
    int flags = 0;

    // Timing, in femtoseconds (from Python, rounded as Amaranth rounds its delays).
    int64_t half_fs;            // half a clock period
    int64_t bit_fs;             // one UART bit
    int64_t bit_and_half_fs;    // a bit and a half: the first data bit's middle
    int64_t machine_fs;         // how often the interlock and alarm pins are set
    int64_t spi_idle_fs;        // how often an idle SPI host looks for a transfer

    int64_t now = 0;
    int64_t next_toggle;        // the clock's next edge
    bool clk = false;
    int64_t cycles = 0;         // rising edges so far (the Python board's Timed.cycles)
    bool power_up_seen = false;

    // The host's transmitter: a byte 8N1 on uart_rx, back to back, woken every bit.
    std::deque<int64_t> to_board;
    int64_t items_started = 0;
    int64_t tx_wake = 0;
    int tx_level_index = -1;    // -1: idle; 0 start bit, 1..8 data, 9 stop; 10: byte done
    int64_t tx_item = 0;

    // The host's receiver: a start bit's falling edge, then each bit in its middle.
    bool rx_sampling = false;
    int64_t rx_wake = 0;
    int rx_bit = 0;
    unsigned rx_value = 0;
    int64_t framing_errors = 0;

    // The SPI host: mode 0, a transfer's bits with SCK at its own rate, cs_n high after.
    std::deque<SPITransfer> spi_queue;
    int64_t transfers_started = 0;
    int64_t spi_wake = 0;
    int spi_step = -1;          // -1 idle; else the step of the transfer (see spi_host)
    SPITransfer spi;

    // The machine: interlock loop and laser alarms, set every machine_fs from t = 0, and the
    // foot switch.
    int64_t machine_wake = 0;
    bool interlock_closed = true, alarms_clear = true, start_pressed = false;
#if GS_FLY
    // The belt's encoder (galvoscan/sim/belt.py): counts a second, the count and its fraction
    // (counts × 10^-15), advanced each machine period; periods left with both lines turned
    // over (a glitch); the axis whose encoder it drives (0: X, 1: Y).
    int64_t belt_rate = 0, belt_count = 0, belt_fraction = 0, belt_glitch = 0;
    int belt_axis = 0;
#endif
    // The inputs io_in of a build with I/O in the queue (bit k for input k), set every
    // machine_fs with the machine's pins; its outputs io_out as last seen (0 at power-up).
    uint32_t io_inputs = 0;
#if GS_IO
    uint32_t last_io_out = 0;
#endif

#if GS_PLAYER
    FlashModel flash;
    bool last_flash_cs_n = true, last_flash_sck = false;
#endif
    // An input set while looking at an edge's state, after the eval that made the next
    // state: evaluated again before that state is committed.
    bool inputs_changed = false;

    // Pins as last seen, for their edges.
    bool last_tx = true, last_xy2_clk = false, last_sync = false, last_prr = false;
    // The head on the STATUS line (galvoscan/sim/head.py): its word (-1: no head), and the
    // bit of its frame it sends (-1: none until SYNC is first seen high at a rising CLOCK).
    int32_t head_word = -1, head_sending = -1;
    int head_bit = -1;
    bool head_last_sync = true;
    uint32_t last_laser = 0;
    int64_t last_pins = -1;

    XY2Receiver receiver;
#if GS_Z
    // The Z line's frames, by the same decoder as X and Y's (Z on both of its inputs).
    XY2Receiver z_receiver;
#endif
    char message[256] = {0};

    // The records, taken by Python in batches (Record order).
    std::vector<int64_t> records[RECORDS];

    uint32_t laser_pins() const {
        return (uint32_t(top.GS_PORT_laser_enable.get<bool>()) << ENABLE) |
               (uint32_t(top.GS_PORT_laser_mo.get<bool>()) << MO) |
               (uint32_t(top.GS_PORT_laser_am.get<bool>()) << AM) |
               (uint32_t(top.GS_PORT_laser_prr.get<bool>()) << PRR) |
               (uint32_t(top.GS_PORT_laser_latch.get<bool>()) << LATCH) |
               (uint32_t(top.GS_PORT_laser_guide.get<bool>()) << GUIDE);
    }

    // The tests' pins (tests/support/sim_board.py): mo, am, prr, interlock_open, latch, power[8],
    // enable, alarm[GS_ALARM_BITS], guide, xy2_sync, from bit 0 up.
    int64_t all_pins() const {
        int64_t pins = int64_t(top.GS_PORT_laser_mo.get<bool>()) |
                       int64_t(top.GS_PORT_laser_am.get<bool>()) << 1 |
                       int64_t(top.GS_PORT_laser_prr.get<bool>()) << 2 |
                       int64_t(top.GS_PORT_interlock_open.get<bool>()) << 3 |
                       int64_t(top.GS_PORT_laser_latch.get<bool>()) << 4 |
                       int64_t(top.GS_PORT_laser_power.get<uint32_t>()) << 5 |
                       int64_t(top.GS_PORT_laser_enable.get<bool>()) << 13;
#if GS_ALARM_BITS > 0
        pins |= int64_t(top.GS_PORT_laser_alarm.get<uint32_t>()) << 14;
#endif
        pins |= int64_t(top.GS_PORT_laser_guide.get<bool>()) << 18 |
                int64_t(top.GS_PORT_xy2_sync.get<bool>()) << 19;
        return pins;
    }

    // Evaluate until nothing changes. (CXXRTL's step() stops after the commit that follows
    // a converged eval, so the outputs it leaves are those from before a clock edge's commit;
    // the eval after that commit brings them up to the new state.)
    void settle() {
        do
            top.eval();
        while (top.commit());
    }

    // A rising edge's new state is looked at lazily: the eval that the next edge needs anyway
    // computes the outputs of that state before it commits the next one, so a clock costs
    // one eval, not two. Whatever reads the pins between edges (a host's sample, an input it
    // sets, the end of a run) catches up first.
    bool stale = false;         // a committed edge whose outputs are not yet evaluated
    int64_t edge_time = 0;      // when the last rising edge came

    bool look_at_edge() {
        if (flags & RECORD_PINS)
            record_pins();
        return watch_pins(edge_time);
    }

    bool catch_up() {
        if (!stale)
            return true;
        settle();
        stale = false;
        return look_at_edge();
    }

    void record_pins() {
        int64_t pins = all_pins();
        if (pins != last_pins) {
            records[PIN_CHANGES].push_back(cycles);
            records[PIN_CHANGES].push_back(pins);
            last_pins = pins;
        }
    }

    // After the design has settled: the edges and changes the Python board's triggers see,
    // in the state the design reached at `at`. Returns false on a protocol error.
    bool watch_pins(int64_t at) {
        bool tx = top.GS_PORT_uart_tx.get<bool>();
        if (last_tx && !tx && !rx_sampling) {
            rx_sampling = true;
            rx_bit = 0;
            rx_value = 0;
            rx_wake = at + bit_and_half_fs;
        }
        last_tx = tx;
        bool xy2_clk = top.GS_PORT_xy2_clk.get<bool>();
        bool sync = top.GS_PORT_xy2_sync.get<bool>();
        bool ok = true;
        if (last_xy2_clk && !xy2_clk) {
            bool x = top.GS_PORT_xy2_x.get<bool>(), y = top.GS_PORT_xy2_y.get<bool>();
            if (flags & RECORD_SAMPLES) {
                records[XY2_SAMPLES].push_back(cycles);
                records[XY2_SAMPLES].push_back(int64_t(sync) | int64_t(x) << 1 |
                                               int64_t(y) << 2);
            }
            int32_t frame_x = 0, frame_y = 0;
            int got = receiver.sample(sync, x, y, frame_x, frame_y, message, sizeof message);
            if (got < 0)
                ok = false;
            else if (got > 0) {
                records[FRAMES].push_back(cycles);
                records[FRAMES].push_back(frame_x);
                records[FRAMES].push_back(frame_y);
            }
#if GS_Z
            bool z = top.GS_PORT_xy2_z.get<bool>();
            int32_t frame_z = 0, unused = 0;
            int got_z = z_receiver.sample(sync, z, z, frame_z, unused, message, sizeof message);
            if (got_z < 0)
                ok = false;
            else if (got_z > 0) {
                records[Z_FRAMES].push_back(cycles);
                records[Z_FRAMES].push_back(frame_z);
            }
#endif
        }
#if GS_HEAD
        if (!last_xy2_clk && xy2_clk) {
            head_bit = (sync && !head_last_sync) ? 0 : (head_bit < 0 ? -1 : head_bit + 1);
            head_last_sync = sync;
            if (head_bit == 0)          // (a head takes its word for a whole frame)
                head_sending = head_word;
            bool level = false;
            if (head_sending >= 0 && head_bit >= 0 && head_bit < 20) {
                // C2 C1 C0 = 001, D15 … D0, even parity over all 20.
                uint32_t frame = (1u << 16 | uint32_t(head_sending)) << 1;
                frame |= uint32_t(__builtin_popcount(frame) & 1);
                level = (frame >> (19 - head_bit)) & 1;
            }
            if (level != top.GS_PORT_xy2_status.get<bool>()) {
                top.GS_PORT_xy2_status.set<bool>(level);
                inputs_changed = true;
            }
        }
#endif
        last_xy2_clk = xy2_clk;
        if (sync && !last_sync)
            records[SYNC_RISES].push_back(cycles);
        last_sync = sync;
        bool prr = top.GS_PORT_laser_prr.get<bool>();
        if (prr && !last_prr && top.GS_PORT_laser_am.get<bool>())
            records[PULSES].push_back(cycles);
        last_prr = prr;
        uint32_t laser = laser_pins();
        if (laser != last_laser) {
            records[LASER_CHANGES].push_back(cycles);
            records[LASER_CHANGES].push_back(laser);
            last_laser = laser;
        }
#if GS_IO
        uint32_t io_out = top.GS_PORT_io_out.get<uint32_t>();
        if (io_out != last_io_out) {
            records[IO_CHANGES].push_back(cycles);
            records[IO_CHANGES].push_back(io_out);
            last_io_out = io_out;
        }
#endif
#if GS_PLAYER
        // The flash, at each change of /CS or SCK (the Python board's trigger), at the time
        // of the clock that made it.
        bool cs_n = top.GS_PORT_flash_cs_n.get<bool>(), sck = top.GS_PORT_flash_clk.get<bool>();
        if (cs_n != last_flash_cs_n || sck != last_flash_sck) {
            last_flash_cs_n = cs_n;
            last_flash_sck = sck;
            bool cipo = flash.pins(cs_n, sck, top.GS_PORT_flash_copi.get<bool>(),
                                   (cycles * 2 * half_fs));
            if (cipo != top.GS_PORT_flash_cipo.get<bool>()) {
                top.GS_PORT_flash_cipo.set<bool>(cipo);
                inputs_changed = true;
            }
        }
#endif
        return ok;
    }

    void set_machine_pins() {
#if GS_FLY
        const int64_t femto = 1000000000000000LL;
        belt_fraction += belt_rate * machine_fs;
        int64_t whole = belt_fraction / femto, left = belt_fraction % femto;
        if (left < 0) {             // (floor division, as Python's)
            left += femto;
            whole -= 1;
        }
        belt_count += whole;
        belt_fraction = left;
        int phase = int(((belt_count % 4) + 4) % 4);     // QUADRATURE_CYCLE: 00 10 11 01
        bool a = phase == 1 || phase == 2, b = phase == 2 || phase == 3;
        if (belt_glitch > 0) {
            a = !a;
            b = !b;
            belt_glitch--;
        }
        top.GS_PORT_encoder_x_a.set<bool>(belt_axis == 0 && a);
        top.GS_PORT_encoder_x_b.set<bool>(belt_axis == 0 && b);
        top.GS_PORT_encoder_y_a.set<bool>(belt_axis == 1 && a);
        top.GS_PORT_encoder_y_b.set<bool>(belt_axis == 1 && b);
#endif
        top.GS_PORT_interlock_open.set<bool>(!interlock_closed);
#if GS_ALARM_BITS > 0
        top.GS_PORT_laser_alarm.set<uint32_t>(alarms_clear ? 0u : (1u << GS_ALARM_BITS) - 1);
#endif
#if GS_PLAYER
        top.GS_PORT_start_n.set<uint32_t>(start_pressed ? 0b10u : 0b11u);
#endif
#if GS_IO
        top.GS_PORT_io_in.set<uint32_t>(io_inputs & 0b11u);
#endif
    }

    void host_transmitter() {
        if (tx_level_index >= 0) {
            tx_level_index++;
            bool bad_stop = tx_item & BAD_STOP;
            if (tx_level_index == 10) {         // the stop bit's time is over
                top.GS_PORT_uart_rx.set<bool>(true);
                tx_level_index = -1;
                if (bad_stop) {                 // the line idles a bit after a break
                    tx_wake += bit_fs;
                    return;
                }
                records[BYTES_IN].push_back(cycles);
                records[BYTES_IN].push_back(tx_item & 0xFF);
            } else {
                bool level = tx_level_index <= 8 ? (tx_item >> (tx_level_index - 1)) & 1
                                                 : !bad_stop;
                top.GS_PORT_uart_rx.set<bool>(level);
                tx_wake += bit_fs;
                return;
            }
        }
        // Idle: the next item, if there is one.
        if (to_board.empty()) {
            tx_wake += bit_fs;
            return;
        }
        tx_item = to_board.front();
        to_board.pop_front();
        items_started++;
        if (tx_item < 0) {                      // a pause
            tx_wake += -tx_item;
            return;
        }
        tx_level_index = 0;
        top.GS_PORT_uart_rx.set<bool>(false);
        tx_wake += bit_fs;
    }

    void host_receiver() {
        bool tx = top.GS_PORT_uart_tx.get<bool>();
        if (rx_bit < 8) {
            rx_value |= unsigned(tx) << rx_bit;
            rx_bit++;
            rx_wake += bit_fs;
            return;
        }
        if (tx)
            records[BYTES_OUT].push_back(rx_value);
        else
            framing_errors++;
        rx_sampling = false;
    }

    // The steps of a transfer (tests/support/sim_board.py's SPI host): after the phase, cs_n low;
    // for each bit, COPI set, half a period, SCK high and CIPO sampled, half a period, SCK
    // low; half a period; cs_n high; four half periods; done.
    void spi_host() {
        if (spi_step < 0) {
            if (spi_queue.empty()) {
                spi_wake += spi_idle_fs;
                return;
            }
            spi = std::move(spi_queue.front());
            spi_queue.pop_front();
            transfers_started++;
            spi_step = 0;
            if (spi.phase_fs) {
                spi_wake += spi.phase_fs;
                return;
            }
        }
        int n = int(spi.bits.size());
        // Step 2i: cs_n low (i = 0) or SCK low, and COPI set to bit i; step 2i + 1: SCK high
        // and CIPO sampled; half a period after each. Step 2n + 1: cs_n high, four half
        // periods; step 2n + 2: done, and the next transfer at once.
        if (spi_step <= 2 * n) {
            if (spi_step % 2 == 0) {
                if (spi_step == 0)
                    top.GS_PORT_spi_cs_n.set<bool>(false);
                else
                    top.GS_PORT_spi_sck.set<bool>(false);
                if (spi_step / 2 < n)
                    top.GS_PORT_spi_copi.set<bool>(spi.bits[spi_step / 2]);
            } else {
                top.GS_PORT_spi_sck.set<bool>(true);
                settle();
                records[SPI_RESULTS].push_back(top.GS_PORT_spi_cipo.get<bool>());
            }
            spi_step++;
            spi_wake += spi.half_fs;
            return;
        }
        if (spi_step == 2 * n + 1) {
            top.GS_PORT_spi_cs_n.set<bool>(true);
            spi_step++;
            spi_wake += 4 * spi.half_fs;
            return;
        }
        records[SPI_RESULTS].push_back(SPI_DONE);
        spi_step = -1;
        spi_host();
    }

    // Run every event before `deadline`; leave those on it for the next run.
    int run_until(int64_t deadline) {
        while (true) {
            int64_t t = next_toggle;
            if (tx_wake < t) t = tx_wake;
            if (rx_sampling && rx_wake < t) t = rx_wake;
            if (spi_wake < t) t = spi_wake;
            if (machine_wake < t) t = machine_wake;
            if (t >= deadline)
                break;
            now = t;
            if (next_toggle == t) {
                clk = !clk;
                top.GS_PORT_clk.set<bool>(clk);
                next_toggle += half_fs;
#if GS_SETTLE_FALLING
                // (A netlist's clock reaches its flip-flops through its input cell, a net of
                // its own: each edge is evaluated until the design settles, and looked at.)
                settle();
                if (clk) {
                    cycles++;
                    edge_time = t;
                    if (!look_at_edge())
                        return PROTOCOL_ERROR;
                }
#else
                if (clk) {
                    bool converged = top.eval();
                    if (stale) {
                        // The outputs this eval computed are the last edge's state's.
                        stale = false;
                        if (!converged)
                            settle();
                        if (!look_at_edge())
                            return PROTOCOL_ERROR;
                        if (inputs_changed)
                            top.eval();         // (the next state, with the new inputs)
                    }
                    inputs_changed = false;
                    top.commit();
                    cycles++;
                    stale = true;
                    edge_time = t;
                } else {
                    // Nothing in the design acts on the falling edge: only note it, so the
                    // next rising one is seen as an edge.
                    top.GS_PREV_CLK = top.GS_PORT_clk;
                }
#endif
            }
            // Then the host's and the machine's processes woken at this instant, in the order
            // the Python board added them: each input it sets settles the design at once.
            bool woken = false;
            bool reads = tx_wake == t || (rx_sampling && rx_wake == t) || spi_wake == t ||
                         machine_wake == t || !power_up_seen;
            if (reads && !catch_up())
                return PROTOCOL_ERROR;
            if (tx_wake == t) {
                host_transmitter();
                woken = true;
            }
            if (rx_sampling && rx_wake == t)
                host_receiver();
            while (spi_wake == t) {
                spi_host();
                woken = true;
            }
            if (machine_wake == t) {
                set_machine_pins();
                machine_wake += machine_fs;
                woken = true;
            }
            if (woken) {
                settle();
                if (!watch_pins(t))
                    return PROTOCOL_ERROR;
            }
            if (!power_up_seen) {
                // The pins as the design is at power-up, its inputs set (the tests' entry 0).
                power_up_seen = true;
                if (flags & RECORD_PINS)
                    record_pins();
            }
        }
        // The last edge's state, so that the records are complete to the deadline.
        if (!catch_up())
            return PROTOCOL_ERROR;
        now = deadline;
        return RAN;
    }
};

// A model that crashes ends the process with one line, not a core dump: the pseudo-terminal
// of a simulated board closes with it, and the host sees its link fail.
void crashed(int signal) {
    static const char line[] = "galvoscan: error: the compiled simulated board crashed "
                               "(run it with --backend python, and report it)\n";
    ssize_t written = write(2, line, sizeof line - 1);
    (void)written;
    _exit(128 + signal);
}

}  // namespace

extern "C" {

// timing: the clock's first edge, half a clock, a UART bit, a bit and a half, the machine's
// period, the idle SPI host's (all fs); flags: Flag bits.
void *gs_board_new(const int64_t *timing, int flags) {
    static bool handlers = false;
    if (!handlers) {
        for (int signal : {SIGSEGV, SIGBUS, SIGFPE, SIGILL})
            std::signal(signal, crashed);
        handlers = true;
    }
    Board *board = new (std::nothrow) Board();
    if (board == nullptr)
        return nullptr;
    board->flags = flags;
    board->next_toggle = timing[0];
    board->half_fs = timing[1];
    board->bit_fs = timing[2];
    board->bit_and_half_fs = timing[3];
    board->machine_fs = timing[4];
    board->spi_idle_fs = timing[5];
    // The ports' initial values (Amaranth's port inits are not in the netlist): the host's
    // UART idles high, the SPI link is deselected, the interlock and alarm pins as the
    // machine has them from the first instant.
    board->top.GS_PORT_uart_rx.set<bool>(true);
    board->top.GS_PORT_spi_cs_n.set<bool>(true);
    board->top.GS_PORT_spi_sck.set<bool>(false);
    board->top.GS_PORT_spi_copi.set<bool>(false);
    board->top.GS_PORT_interlock_open.set<bool>(true);
#if GS_PLAYER
    board->top.GS_PORT_start_n.set<uint32_t>(0b11u);
    board->top.GS_PORT_flash_cipo.set<bool>(true);
#endif
#if GS_ALARM_BITS > 0
    board->top.GS_PORT_laser_alarm.set<uint32_t>((1u << GS_ALARM_BITS) - 1);
#endif
#ifdef GS_PORT_rst
    board->top.GS_PORT_rst.set<bool>(false);
#endif
    board->top.GS_PORT_clk.set<bool>(false);
    board->settle();
    board->last_tx = board->top.GS_PORT_uart_tx.get<bool>();
    board->last_laser = board->laser_pins();
    // The Python board's recorder sees the pins once as the design first settles.
    board->records[LASER_CHANGES].push_back(0);
    board->records[LASER_CHANGES].push_back(board->last_laser);
    return board;
}

void gs_board_free(void *board) { delete static_cast<Board *>(board); }

// Items for the host's UART transmitter: bytes, BAD_STOP | byte, or -pause_fs.
void gs_board_send(void *handle, const int64_t *items, int64_t size) {
    Board *board = static_cast<Board *>(handle);
    board->to_board.insert(board->to_board.end(), items, items + size);
}

// One SPI transfer: `size` bits (0 or 1 each), SCK's half period and the phase (fs).
void gs_board_spi(void *handle, const uint8_t *bits, int64_t size, int64_t half_fs,
                  int64_t phase_fs) {
    Board *board = static_cast<Board *>(handle);
    board->spi_queue.push_back(SPITransfer{std::vector<uint8_t>(bits, bits + size), half_fs,
                                           phase_fs});
}

void gs_board_machine(void *handle, int interlock_closed, int alarms_clear) {
    Board *board = static_cast<Board *>(handle);
    board->interlock_closed = interlock_closed;
    board->alarms_clear = alarms_clear;
}

// The head's status word on its STATUS line (-1: no head; a build with the receiver).
void gs_board_head(void *handle, int word) { static_cast<Board *>(handle)->head_word = word; }

// The belt (a build that marks on the fly): its rate in counts a second, its axis (0: X,
// 1: Y), and machine periods of glitch to add. Returns its count (any build: 0 without).
int64_t gs_board_belt(void *handle, int64_t counts_per_s, int axis, int64_t glitch) {
#if GS_FLY
    Board *board = static_cast<Board *>(handle);
    board->belt_rate = counts_per_s;
    board->belt_axis = axis;
    board->belt_glitch += glitch;
    return board->belt_count;
#else
    return 0;
#endif
}

// The foot switch on start_n (a build with the job player).
void gs_board_start(void *handle, int pressed) {
    static_cast<Board *>(handle)->start_pressed = pressed;
}

// The inputs io_in, bit k for input k (a build with I/O in the queue; the machine's period).
void gs_board_io(void *handle, int64_t inputs) {
    static_cast<Board *>(handle)->io_inputs = uint32_t(inputs);
}

// The flash's contents from `address` on, and whether it starts in deep power-down.
// Returns 0, or -1 on a build without the player (no flash) or past the flash's end.
int gs_board_flash(void *handle, int64_t address, const uint8_t *data, int64_t size,
                   int powered_down) {
#if GS_PLAYER
    Board *board = static_cast<Board *>(handle);
    if (address < 0 || size < 0 || address + size > FlashModel::BYTES)
        return -1;
    std::memcpy(board->flash.memory.data() + address, data, size_t(size));
    board->flash.powered_down = powered_down;
    return 0;
#else
    (void)handle, (void)address, (void)data, (void)size, (void)powered_down;
    return -1;
#endif
}

int gs_board_run_until(void *handle, int64_t deadline_fs) {
    return static_cast<Board *>(handle)->run_until(deadline_fs);
}

const char *gs_board_message(void *handle) { return static_cast<Board *>(handle)->message; }

// 0 UART items started, 1 framing errors, 2 rising clock edges, 3 the board's time (fs),
// 4 SPI transfers started, 5 flash instructions carried out, 6 flash instructions ignored.
int64_t gs_board_counter(void *handle, int which) {
    Board *board = static_cast<Board *>(handle);
    switch (which) {
    case 0: return board->items_started;
    case 1: return board->framing_errors;
    case 2: return board->cycles;
    case 3: return board->now;
    case 4: return board->transfers_started;
#if GS_PLAYER
    case 5: return board->flash.commands;
    case 6: return board->flash.ignored;
#endif
    }
    return -1;
}

// What a run leaves for Python in one call (a host that polls in steps of a UART bit makes
// hundreds of thousands of runs, and a call each for the counters and every record cost more
// than the clocks they ran): out[0] UART items started, out[1] framing errors, out[2] SPI
// transfers started, out[3] a bit for each record (Record) that holds values.
void gs_board_status(void *handle, int64_t *out) {
    Board *board = static_cast<Board *>(handle);
    out[0] = board->items_started;
    out[1] = board->framing_errors;
    out[2] = board->transfers_started;
    int64_t pending = 0;
    for (int which = 0; which < RECORDS; which++)
        if (!board->records[which].empty())
            pending |= int64_t(1) << which;
    out[3] = pending;
}

// Record `which` (Record): copy up to `capacity` values into `out`, drop them from the
// board, return how many.
int64_t gs_board_take(void *handle, int which, int64_t *out, int64_t capacity) {
    Board *board = static_cast<Board *>(handle);
    if (which < 0 || which >= RECORDS)
        return -1;
    std::vector<int64_t> &record = board->records[which];
    int64_t n = int64_t(record.size()) < capacity ? int64_t(record.size()) : capacity;
    if (n > 0) {
        std::memcpy(out, record.data(), size_t(n) * sizeof(int64_t));
        record.erase(record.begin(), record.begin() + n);
    }
    return n;
}

// For the tests of the crash handler only: a model that fails as a broken one would.
void gs_board_crash(void *) { std::raise(SIGSEGV); }

}  // extern "C"
