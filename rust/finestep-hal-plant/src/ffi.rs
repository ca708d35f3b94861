//! The C ABI `linuxcnc/fsplant.c` calls (prototypes in `linuxcnc/fsplant.h`): scalars and
//! out-pointers only; every call catches a panic and reports it as a failure.

use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::StepgenPlant;

/// A new plant (see [`StepgenPlant::new`]), or null (the reason printed to stderr). The
/// pointer returned is freed once with [`fs_plant_free`].
#[no_mangle]
pub extern "C" fn fs_plant_new(
    axes: u32,
    tau_clocks: u64,
    counts_per_step: u32,
    slot_clocks: u64,
    slots_per_period: u64,
) -> *mut StepgenPlant {
    let made =
        catch_unwind(|| StepgenPlant::new(axes as usize, tau_clocks, counts_per_step, slot_clocks, slots_per_period));
    match made {
        Ok(Ok(plant)) => Box::into_raw(Box::new(plant)),
        Ok(Err(e)) => {
            eprintln!("fsplant: {e}");
            std::ptr::null_mut()
        }
        Err(_) => std::ptr::null_mut(),
    }
}

/// Frees a plant from [`fs_plant_new`].
///
/// # Safety
///
/// `plant` is null or from [`fs_plant_new`], not freed before, and no other call uses it.
#[no_mangle]
pub unsafe extern "C" fn fs_plant_free(plant: *mut StepgenPlant) {
    if !plant.is_null() {
        // SAFETY: the caller passes a pointer from Box::into_raw, once.
        drop(unsafe { Box::from_raw(plant) });
    }
}

/// [`StepgenPlant::gate`]: 0, or -1 when the wait timed out.
///
/// # Safety
///
/// `plant` is from [`fs_plant_new`] and not freed.
#[no_mangle]
pub unsafe extern "C" fn fs_plant_gate(plant: *const StepgenPlant) -> i32 {
    // SAFETY: the caller's contract.
    let plant = unsafe { &*plant };
    match catch_unwind(AssertUnwindSafe(|| plant.gate())) {
        Ok(Ok(())) => 0,
        _ => -1,
    }
}

/// [`StepgenPlant::sample`].
///
/// # Safety
///
/// `plant` is from [`fs_plant_new`] and not freed.
#[no_mangle]
pub unsafe extern "C" fn fs_plant_sample(plant: *const StepgenPlant, levels: u32) {
    // SAFETY: the caller's contract.
    let plant = unsafe { &*plant };
    let _ = catch_unwind(AssertUnwindSafe(|| plant.sample(levels)));
}

/// [`StepgenPlant::read`] into `counts[0..n]`: 0, or -1 when the wait timed out (the
/// counts are written all the same).
///
/// # Safety
///
/// `plant` is from [`fs_plant_new`] and not freed; `counts` points to `n` writable values.
#[no_mangle]
pub unsafe extern "C" fn fs_plant_read(plant: *const StepgenPlant, counts: *mut i64, n: u32) -> i32 {
    // SAFETY: the caller's contract.
    let (plant, counts) = unsafe { (&*plant, std::slice::from_raw_parts_mut(counts, n as usize)) };
    match catch_unwind(AssertUnwindSafe(|| plant.read(counts))) {
        Ok(Ok(())) => 0,
        _ => -1,
    }
}

/// [`StepgenPlant::write`].
///
/// # Safety
///
/// `plant` is from [`fs_plant_new`] and not freed.
#[no_mangle]
pub unsafe extern "C" fn fs_plant_write(plant: *const StepgenPlant) {
    // SAFETY: the caller's contract.
    let plant = unsafe { &*plant };
    let _ = catch_unwind(AssertUnwindSafe(|| plant.write()));
}

/// [`StepgenPlant::sync_errors`].
///
/// # Safety
///
/// `plant` is from [`fs_plant_new`] and not freed.
#[no_mangle]
pub unsafe extern "C" fn fs_plant_sync_errors(plant: *const StepgenPlant) -> u32 {
    // SAFETY: the caller's contract.
    let plant = unsafe { &*plant };
    catch_unwind(AssertUnwindSafe(|| plant.sync_errors())).unwrap_or(u32::MAX)
}
