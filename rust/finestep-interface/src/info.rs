//! A table of the whole map ([`crate::regs::REGISTERS`]) for code that walks every
//! register: register dumps in the host driver, tests that cover every field.

use crate::{Access, Field};

/// One register (or register array) of the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RegisterInfo {
    /// UPPER_SNAKE name, as in the map.
    pub name: &'static str,
    /// Word address (of element 0 for an array).
    pub addr: u8,
    /// Present when the register repeats.
    pub array: Option<ArrayInfo>,
    /// The map's description.
    pub description: &'static str,
    /// The fields, in map order.
    pub fields: &'static [FieldInfo],
    /// What a read returns right after reset when the map fixes every field then
    /// (`rw` reset values, `ro` fixed values, 0 for `pulse`); `None` when some field is
    /// a hardware value.
    pub reset_word: Option<u32>,
}

/// How an array register repeats: element `i` is at `addr + i * stride`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArrayInfo {
    /// Number of elements.
    pub count: usize,
    /// Address distance between elements.
    pub stride: u8,
}

/// One field of a register.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FieldInfo {
    /// UPPER_SNAKE name, as in the map.
    pub name: &'static str,
    /// Where it sits in the word.
    pub field: Field,
    /// How the host may access it.
    pub access: Access,
    /// Value after reset (`rw` fields).
    pub reset: Option<u32>,
    /// Fixed value (`ro` fields that have one).
    pub value: Option<u32>,
    /// The map's description.
    pub description: &'static str,
}

impl RegisterInfo {
    /// Number of elements: the array count, or 1.
    pub fn count(&self) -> usize {
        self.array.map_or(1, |array| array.count)
    }

    /// Word address of element `index`, or `None` past the last element.
    pub fn addr_of(&self, index: usize) -> Option<u8> {
        if index >= self.count() {
            return None;
        }
        let stride = self.array.map_or(0, |array| usize::from(array.stride));
        u8::try_from(usize::from(self.addr) + index * stride).ok()
    }

    /// The field called `name`, if the register has one.
    pub fn field(&self, name: &str) -> Option<&'static FieldInfo> {
        self.fields.iter().find(|field| field.name == name)
    }
}
