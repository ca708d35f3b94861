//! [`Field`]: where a bit field sits in a register word, and how to read and write it.

/// A bit field of a 32-bit register word: `width` bits starting at bit `lsb`.
///
/// The generated constants in [`crate::regs`] all satisfy `1 <= width` and
/// `lsb + width <= 32`. For a hand-made `Field` outside that range the methods stay
/// total: bits beyond bit 31 simply do not exist (they read 0 and writes drop them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Field {
    /// Lowest bit of the field.
    pub lsb: u32,
    /// Number of bits.
    pub width: u32,
}

impl Field {
    /// The largest value the field holds: `width` ones.
    pub const fn max(self) -> u32 {
        if self.width >= u32::BITS {
            u32::MAX
        } else {
            (1 << self.width) - 1
        }
    }

    /// The field's bits in place within the word.
    pub const fn mask(self) -> u32 {
        shift_left(self.max(), self.lsb)
    }

    /// Whether `value` fits in the field unchanged.
    pub const fn fits(self, value: u32) -> bool {
        value <= self.max()
    }

    /// The field's value in `word`, shifted down to bit 0.
    pub const fn get(self, word: u32) -> u32 {
        match word.checked_shr(self.lsb) {
            Some(shifted) => shifted & self.max(),
            None => 0,
        }
    }

    /// `word` with the field replaced by `value`; every other bit is kept.
    ///
    /// `value` must fit the field ([`Field::fits`]): debug builds panic when it does not
    /// (a value too big for its field is a driver bug worth finding), release builds
    /// keep only its low `width` bits, so a bad value never reaches a neighbouring field.
    pub const fn set(self, word: u32, value: u32) -> u32 {
        debug_assert!(self.fits(value), "value does not fit in the register field");
        (word & !self.mask()) | (shift_left(value, self.lsb) & self.mask())
    }
}

/// `value << amount`, 0 once every bit has been shifted out.
const fn shift_left(value: u32, amount: u32) -> u32 {
    match value.checked_shl(amount) {
        Some(shifted) => shifted,
        None => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::Field;

    #[test]
    fn mask_get_and_set_of_a_middle_field() {
        let field = Field { lsb: 4, width: 3 };
        assert_eq!(field.max(), 0b111);
        assert_eq!(field.mask(), 0b111_0000);
        assert_eq!(field.get(0xFFFF_FF5F), 0b101);
        assert_eq!(field.set(0xFFFF_FFFF, 0b010), 0xFFFF_FFAF);
        assert_eq!(field.set(0, 0b111), 0b111_0000);
    }

    #[test]
    fn full_word_field() {
        let field = Field { lsb: 0, width: 32 };
        assert_eq!(field.max(), u32::MAX);
        assert_eq!(field.mask(), u32::MAX);
        assert_eq!(field.get(0x1234_5678), 0x1234_5678);
        assert_eq!(field.set(0xFFFF_FFFF, 0x1234_5678), 0x1234_5678);
    }

    #[test]
    fn top_bit_field() {
        let field = Field { lsb: 31, width: 1 };
        assert_eq!(field.mask(), 0x8000_0000);
        assert_eq!(field.get(0x8000_0000), 1);
        assert_eq!(field.set(0x7FFF_FFFF, 1), u32::MAX);
    }

    #[test]
    fn fits_is_the_boundary_of_max() {
        let field = Field { lsb: 8, width: 5 };
        assert!(field.fits(31));
        assert!(!field.fits(32));
    }

    #[test]
    fn out_of_word_fields_are_total() {
        let beyond = Field { lsb: 32, width: 4 };
        assert_eq!(beyond.mask(), 0);
        assert_eq!(beyond.get(u32::MAX), 0);
        assert_eq!(beyond.set(0x55, 0xF), 0x55);
        let empty = Field { lsb: 3, width: 0 };
        assert_eq!(empty.mask(), 0);
        assert_eq!(empty.get(u32::MAX), 0);
    }

    #[test]
    #[cfg(debug_assertions)]
    #[should_panic(expected = "does not fit")]
    fn set_rejects_a_value_too_wide_in_debug_builds() {
        Field { lsb: 0, width: 2 }.set(0, 4);
    }

    #[test]
    #[cfg(not(debug_assertions))]
    fn set_truncates_a_value_too_wide_in_release_builds() {
        // Bit 2 of the value must not leak into bit 2 of the word.
        assert_eq!(Field { lsb: 0, width: 2 }.set(0, 0b111), 0b011);
    }
}
