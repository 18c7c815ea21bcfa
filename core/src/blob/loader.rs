//! The loading entry points every 4-byte model family shares, generated around the family's
//! own validation `fn fill(&mut self, payload: &Payload<'_>, stored: ScalarKind)`.

/// Expands, inside an `impl` of a model type with `const fn new()` and `fill`, to
/// `from_blob`, `load`, `from_payload`, `load_payload` and the private `clear`. `$what` names
/// the model in docs and defmt warnings, `$errors` documents `from_blob`'s errors.
macro_rules! loader_methods {
    ($payload:ident, $what:literal, $errors:literal) => {
        #[doc = concat!("Decodes and validates a ", $what, " blob, converting its words to `S`.")]
        ///
        /// # Errors
        #[doc = $errors]
        pub fn from_blob(bytes: &[u8]) -> Result<Self, BlobError> {
            let mut model = Self::new();
            model.load(bytes)?;
            Ok(model)
        }

        #[doc = concat!("Replaces this ", $what, " by the one in `bytes`, in place. On error it is left empty.")]
        ///
        /// # Errors
        /// As [`Self::from_blob`].
        pub fn load(&mut self, bytes: &[u8]) -> Result<(), BlobError> {
            self.clear();
            let result = $payload::from_blob(bytes)
                .and_then(|(header, payload)| self.load_payload(&payload, header.scalar));
            #[cfg(feature = "defmt")]
            if let Err(e) = &result {
                defmt::warn!("{=str} blob rejected: {}", $what, e);
            }
            result
        }

        /// Validates a decoded payload whose words are stored as `stored`.
        ///
        /// # Errors
        /// As [`Self::from_blob`], minus framing.
        pub fn from_payload(payload: &$payload<'_>, stored: ScalarKind) -> Result<Self, BlobError> {
            let mut model = Self::new();
            model.load_payload(payload, stored)?;
            Ok(model)
        }

        #[doc = concat!("Replaces this ", $what, " by a decoded payload, in place. On error it is left empty.")]
        ///
        /// # Errors
        /// As [`Self::from_payload`].
        pub fn load_payload(
            &mut self,
            payload: &$payload<'_>,
            stored: ScalarKind,
        ) -> Result<(), BlobError> {
            let result = self.fill(payload, stored);
            if result.is_err() {
                self.clear();
            }
            result
        }

        fn clear(&mut self) {
            *self = Self::new();
        }
    };
}

pub(crate) use loader_methods;
