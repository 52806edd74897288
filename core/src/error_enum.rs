//! [`error_enum!`]: an error type whose every variant has one fixed message, for the core's
//! input errors that carry no data.

/// Defines an error enum whose variants each carry one fixed message: the enum (`Debug`,
/// `Clone`, `Copy`, `PartialEq`, `Eq`, `#[non_exhaustive]`), `Display` writing the variant's
/// message, and `core::error::Error`.
///
/// ```ignore
/// error_enum! {
///     /// Why a pose was rejected.
///     pub enum PoseError {
///         /// A component is NaN or infinite.
///         NonFinite => "pose has a non-finite component",
///     }
/// }
/// ```
macro_rules! error_enum {
    (
        $(#[$meta:meta])*
        pub enum $name:ident {
            $( $(#[$variant_meta:meta])* $variant:ident => $message:literal, )+
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        #[non_exhaustive]
        pub enum $name {
            $( $(#[$variant_meta])* $variant, )+
        }

        impl core::fmt::Display for $name {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str(match self {
                    $( Self::$variant => $message, )+
                })
            }
        }

        impl core::error::Error for $name {}
    };
}
