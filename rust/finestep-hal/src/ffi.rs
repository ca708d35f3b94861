//! The C ABI the realtime module `linuxcnc/finestep.c` calls (prototypes in
//! `linuxcnc/finestep_hal.h`). Scalars and out-pointers only, no shared structs: the HAL
//! pins and parameters stay in C, the driver in Rust. Every function returns 0 on
//! success and -1 on failure, the message then in [`fs_hal_last_error`]; a null handle
//! or pointer is a failure, never a crash, and no panic crosses the boundary.

use std::ffi::{c_char, c_int, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::{Driver, EncoderCommand, StepgenCommand};

/// The driver and its last error, behind the opaque `struct fs_hal *` of C.
pub struct Handle {
    driver: Driver,
    error: String,
    errors: u32,
}

fn copy_message(message: &str, buf: *mut c_char, len: usize) {
    if buf.is_null() || len == 0 {
        return;
    }
    let bytes = message.as_bytes();
    let n = bytes.len().min(len - 1);
    // SAFETY: the caller gives `buf` with room for `len` bytes.
    unsafe {
        std::ptr::copy_nonoverlapping(bytes.as_ptr().cast::<c_char>(), buf, n);
        *buf.add(n) = 0;
    }
}

fn guarded(handle: *mut Handle, f: impl FnOnce(&mut Handle) -> Result<(), String>) -> c_int {
    // SAFETY: a non-null handle came from fs_hal_open and is used by one thread at a time.
    let Some(h) = (unsafe { handle.as_mut() }) else { return -1 };
    let outcome = catch_unwind(AssertUnwindSafe(|| f(h))).unwrap_or_else(|_| Err("the driver panicked".into()));
    match outcome {
        Ok(()) => 0,
        Err(message) => {
            h.error = message;
            h.errors = h.errors.wrapping_add(1);
            -1
        }
    }
}

/// Opens the chip on `bus` (`spidev:/dev/spidevB.C[@SCK_HZ]` or `sim:SOCKET`); null on
/// failure, with the message in `err` (`err_len` bytes, NUL-terminated).
///
/// # Safety
/// `bus` is a NUL-terminated string; `err` has room for `err_len` bytes (or is null).
#[no_mangle]
pub unsafe extern "C" fn fs_hal_open(bus: *const c_char, err: *mut c_char, err_len: usize) -> *mut Handle {
    if bus.is_null() {
        copy_message("no bus given", err, err_len);
        return std::ptr::null_mut();
    }
    // SAFETY: the caller passes a NUL-terminated string.
    let bus = unsafe { CStr::from_ptr(bus) }.to_string_lossy().into_owned();
    match catch_unwind(|| Driver::open(&bus)) {
        Ok(Ok(driver)) => Box::into_raw(Box::new(Handle { driver, error: String::new(), errors: 0 })),
        Ok(Err(e)) => {
            copy_message(&e.to_string(), err, err_len);
            std::ptr::null_mut()
        }
        Err(_) => {
            copy_message("the driver panicked while opening", err, err_len);
            std::ptr::null_mut()
        }
    }
}

/// Closes the link (the chip keeps running what it has; its watchdog stops it).
///
/// # Safety
/// `handle` came from [`fs_hal_open`] and is not used again.
#[no_mangle]
pub unsafe extern "C" fn fs_hal_close(handle: *mut Handle) {
    if !handle.is_null() {
        // SAFETY: from Box::into_raw in fs_hal_open, closed once.
        drop(unsafe { Box::from_raw(handle) });
    }
}

/// Step generators, encoder channels and the core clock the chip reports (CAPS, CLOCK_HZ).
///
/// # Safety
/// `handle` from [`fs_hal_open`]; the out-pointers are valid or null.
#[no_mangle]
pub unsafe extern "C" fn fs_hal_caps(
    handle: *const Handle,
    n_axes: *mut u32,
    n_enc: *mut u32,
    clock_hz: *mut u32,
    paced: *mut c_int,
) -> c_int {
    // SAFETY: see above.
    let Some(h) = (unsafe { handle.as_ref() }) else { return -1 };
    // SAFETY: each pointer is valid or null.
    unsafe {
        if let Some(p) = n_axes.as_mut() {
            *p = h.driver.n_axes() as u32;
        }
        if let Some(p) = n_enc.as_mut() {
            *p = h.driver.n_enc() as u32;
        }
        if let Some(p) = clock_hz.as_mut() {
            *p = h.driver.clock_hz();
        }
        if let Some(p) = paced.as_mut() {
            *p = c_int::from(h.driver.paced());
        }
    }
    0
}

/// Sets stepgen `axis`'s pins and parameters for the next write (timing in ns,
/// `step_type` 0 step/dir, 1 up/down, 2 quadrature).
///
/// # Safety
/// `handle` from [`fs_hal_open`].
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fs_hal_set_stepgen(
    handle: *mut Handle,
    axis: u32,
    position_cmd: f64,
    position_scale: f64,
    maxvel: f64,
    maxaccel: f64,
    enable: c_int,
    steplen_ns: u32,
    stepspace_ns: u32,
    dirsetup_ns: u32,
    dirhold_ns: u32,
    step_type: u32,
) -> c_int {
    let cmd = StepgenCommand {
        position_cmd,
        position_scale,
        maxvel,
        maxaccel,
        enable: enable != 0,
        timing_ns: [steplen_ns, stepspace_ns, dirsetup_ns, dirhold_ns],
        step_type,
    };
    guarded(handle, |h| h.driver.set_stepgen(axis as usize, cmd).map_err(|e| e.to_string()))
}

/// Sets encoder `channel`'s pins and parameters for the next read.
///
/// # Safety
/// `handle` from [`fs_hal_open`].
#[no_mangle]
pub unsafe extern "C" fn fs_hal_set_encoder(
    handle: *mut Handle,
    channel: u32,
    scale: f64,
    reset: c_int,
    counter_mode: c_int,
    filter: c_int,
    index_enable: c_int,
) -> c_int {
    let cmd = EncoderCommand {
        scale,
        reset: reset != 0,
        counter_mode: counter_mode != 0,
        filter: filter != 0,
        index_enable: index_enable != 0,
    };
    guarded(handle, |h| h.driver.set_encoder(channel as usize, cmd).map_err(|e| e.to_string()))
}

/// `finestep.0.read`: one coherent latched read.
///
/// # Safety
/// `handle` from [`fs_hal_open`].
#[no_mangle]
pub unsafe extern "C" fn fs_hal_read(handle: *mut Handle, period_ns: i64) -> c_int {
    guarded(handle, |h| h.driver.read(period_ns).map_err(|e| e.to_string()))
}

/// `finestep.0.write`: one period record (and, on a simulated chip, one core period).
///
/// # Safety
/// `handle` from [`fs_hal_open`].
#[no_mangle]
pub unsafe extern "C" fn fs_hal_write(
    handle: *mut Handle,
    period_ns: i64,
    enable: c_int,
    watchdog_timeout_ns: u32,
) -> c_int {
    guarded(handle, |h| h.driver.write_set(period_ns, enable != 0, watchdog_timeout_ns).map_err(|e| e.to_string()))
}

/// What the last read gave for stepgen `axis`.
///
/// # Safety
/// `handle` from [`fs_hal_open`]; the out-pointers are valid or null.
#[no_mangle]
pub unsafe extern "C" fn fs_hal_stepgen(
    handle: *mut Handle,
    axis: u32,
    counts: *mut i32,
    position_fb: *mut f64,
    velocity_fb: *mut f64,
    limited: *mut u32,
) -> c_int {
    guarded(handle, |h| {
        let fb = h.driver.stepgen_feedback(axis as usize).ok_or_else(|| format!("no stepgen {axis}"))?;
        // SAFETY: each pointer is valid or null.
        unsafe {
            if let Some(p) = counts.as_mut() {
                *p = fb.counts;
            }
            if let Some(p) = position_fb.as_mut() {
                *p = fb.position_fb;
            }
            if let Some(p) = velocity_fb.as_mut() {
                *p = fb.velocity_fb;
            }
            if let Some(p) = limited.as_mut() {
                *p = fb.limited;
            }
        }
        Ok(())
    })
}

/// What the last read gave for encoder `channel`.
///
/// # Safety
/// `handle` from [`fs_hal_open`]; the out-pointers are valid or null.
#[no_mangle]
pub unsafe extern "C" fn fs_hal_encoder(
    handle: *mut Handle,
    channel: u32,
    count: *mut i32,
    position: *mut f64,
    velocity: *mut f64,
    index_enable: *mut c_int,
) -> c_int {
    guarded(handle, |h| {
        let fb = h.driver.encoder_feedback(channel as usize).ok_or_else(|| format!("no encoder {channel}"))?;
        // SAFETY: each pointer is valid or null.
        unsafe {
            if let Some(p) = count.as_mut() {
                *p = fb.count;
            }
            if let Some(p) = position.as_mut() {
                *p = fb.position;
            }
            if let Some(p) = velocity.as_mut() {
                *p = fb.velocity;
            }
            if let Some(p) = index_enable.as_mut() {
                *p = fb.index_enable.into();
            }
        }
        Ok(())
    })
}

/// The hand wheel at the last read: `count` in quadrature edges, `detents` (4 edges).
///
/// # Safety
/// `handle` from [`fs_hal_open`]; the out-pointers are valid or null.
#[no_mangle]
pub unsafe extern "C" fn fs_hal_mpg(handle: *mut Handle, count: *mut i32, detents: *mut i32) -> c_int {
    guarded(handle, |h| {
        let (edges, turns) = h.driver.hand_wheel();
        // SAFETY: each pointer is valid or null.
        unsafe {
            if let Some(p) = count.as_mut() {
                *p = edges;
            }
            if let Some(p) = detents.as_mut() {
                *p = turns;
            }
        }
        Ok(())
    })
}

/// Turns a simulated chip's hand wheel by `edges` quadrature edges while its time
/// passes (a test's wheel); fails on a board, whose wheel the operator turns.
///
/// # Safety
/// `handle` from [`fs_hal_open`].
#[no_mangle]
pub unsafe extern "C" fn fs_hal_turn_wheel(handle: *mut Handle, edges: i64) -> c_int {
    guarded(handle, |h| match h.driver.turn_wheel(edges).map_err(|e| e.to_string())? {
        true => Ok(()),
        false => Err("the hand wheel of this chip cannot be turned from the host".into()),
    })
}

/// The status pins: E-stop input released, watchdog bit, running; `clear_watchdog`
/// re-arms the watchdog bit (the HAL user wrote has_bit false).
///
/// # Safety
/// `handle` from [`fs_hal_open`]; the out-pointers are valid or null.
#[no_mangle]
pub unsafe extern "C" fn fs_hal_status(
    handle: *mut Handle,
    clear_watchdog: c_int,
    estop_ok: *mut c_int,
    watchdog_bit: *mut c_int,
    running: *mut c_int,
) -> c_int {
    guarded(handle, |h| {
        if clear_watchdog != 0 {
            h.driver.clear_watchdog_bit();
        }
        let status = h.driver.status();
        // SAFETY: each pointer is valid or null.
        unsafe {
            if let Some(p) = estop_ok.as_mut() {
                *p = c_int::from(status.estop_ok);
            }
            if let Some(p) = watchdog_bit.as_mut() {
                *p = c_int::from(status.watchdog_bit);
            }
            if let Some(p) = running.as_mut() {
                *p = c_int::from(status.running);
            }
        }
        Ok(())
    })
}

/// Copies the last error into `buf` (`len` bytes, NUL-terminated) and returns how many
/// errors there have been (so C prints each once).
///
/// # Safety
/// `handle` from [`fs_hal_open`]; `buf` has room for `len` bytes (or is null).
#[no_mangle]
pub unsafe extern "C" fn fs_hal_last_error(handle: *const Handle, buf: *mut c_char, len: usize) -> u32 {
    // SAFETY: see above.
    let Some(h) = (unsafe { handle.as_ref() }) else { return 0 };
    copy_message(&h.error, buf, len);
    h.errors
}

#[cfg(test)]
mod tests {
    /// The C prototypes in `linuxcnc/finestep_hal.h`, each as its name and parameter
    /// types spelled the Rust way, against the `extern "C"` functions of this file: the
    /// two sides of the ABI are written twice, so they are checked against each other.
    fn c_type(param: &str) -> String {
        let param = param.trim();
        let (ty, pointer) = match param.rfind('*') {
            Some(star) => (param[..star].trim(), true),
            None => (param.rsplit_once(' ').map_or(param, |(ty, _)| ty).trim(), false),
        };
        let (ty, constant) = match ty.strip_prefix("const ") {
            Some(rest) => (rest, true),
            None => (ty, false),
        };
        let base = match ty {
            "struct fs_hal" => "Handle",
            "char" => "c_char",
            "int" => "c_int",
            "double" => "f64",
            "uint32_t" => "u32",
            "int32_t" => "i32",
            "int64_t" => "i64",
            "size_t" => "usize",
            other => panic!("a C type the check does not know: {other}"),
        };
        match (pointer, constant) {
            (true, true) => format!("*const {base}"),
            (true, false) => format!("*mut {base}"),
            (false, _) => base.to_string(),
        }
    }

    fn prototypes(text: &str, start: &str, split: fn(&str) -> Vec<String>) -> Vec<(String, Vec<String>)> {
        let mut found = Vec::new();
        let mut rest = text;
        while let Some(at) = rest.find(start) {
            let tail = &rest[at + start.len()..];
            let name_end = tail.find('(').expect("a parameter list");
            let name = format!("fs_hal_{}", &tail[..name_end]);
            let params_end = tail.find(')').expect("the end of the parameter list");
            let params = tail[name_end + 1..params_end].trim().trim_end_matches(',');
            found.push((name, if params.is_empty() { Vec::new() } else { split(params) }));
            rest = &tail[params_end..];
        }
        found.sort();
        found
    }

    #[test]
    fn the_c_header_declares_exactly_these_functions() {
        let header =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../linuxcnc/finestep_hal.h")).unwrap();
        // Statements outside the comments, each prototype spelled with its name last.
        let code: String =
            header.split("/*").map(|part| part.split_once("*/").map_or(part, |(_, code)| code)).collect();
        let statements: String = code
            .split(';')
            .filter(|s| s.contains("fs_hal_") && s.contains('('))
            .map(|s| s.replace("*fs_hal_", "* fs_hal_"))
            .collect::<Vec<_>>()
            .join(";");
        let c = prototypes(&statements, " fs_hal_", |params| params.split(',').map(c_type).collect());
        let rust = prototypes(include_str!("ffi.rs"), "extern \"C\" fn fs_hal_", |params| {
            params.split(',').map(|p| p.split_once(':').expect("name: type").1.trim().to_string()).collect()
        });
        assert_eq!(c.len(), 13, "{c:?}");
        assert_eq!(c, rust);
    }
}
