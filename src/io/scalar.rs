//! PLY scalar types and their decoding from raw bytes in either byte order.

/// One of the eight PLY scalar types.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// Size in bytes in a binary payload.
    pub const fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// The name the PLY header uses (the classic one, as most tools write it).
    pub const fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    pub const fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Decodes the value at the start of `b` (which holds at least `size()` bytes) as f64.
    /// Every PLY scalar is exactly representable in f64.
    #[inline(always)]
    pub fn read(self, b: &[u8], big_endian: bool) -> f64 {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = b[..$n].try_into().unwrap();
                (if big_endian {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => get!(i16, 2),
            Scalar::U16 => get!(u16, 2),
            Scalar::I32 => get!(i32, 4),
            Scalar::U32 => get!(u32, 4),
            Scalar::F32 => get!(f32, 4),
            Scalar::F64 => get!(f64, 8),
        }
    }

    /// Decodes an integer (list counts and indices); `None` for float types.
    #[inline(always)]
    pub fn read_int(self, b: &[u8], big_endian: bool) -> Option<i64> {
        (!self.is_float()).then(|| self.read(b, big_endian) as i64)
    }

    /// Appends `value` in this type's binary encoding (values out of range saturate).
    pub fn write(self, out: &mut Vec<u8>, value: f64, big_endian: bool) {
        macro_rules! put {
            ($t:ty) => {{
                let v = value as $t;
                out.extend_from_slice(&if big_endian {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                });
            }};
        }
        match self {
            Scalar::I8 => put!(i8),
            Scalar::U8 => put!(u8),
            Scalar::I16 => put!(i16),
            Scalar::U16 => put!(u16),
            Scalar::I32 => put!(i32),
            Scalar::U32 => put!(u32),
            Scalar::F32 => put!(f32),
            Scalar::F64 => put!(f64),
        }
    }
}
