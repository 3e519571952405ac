//! Errors of the render layer (`render`): the GPU side, independent of files. An invalid
//! argument (size, target format, meshes) is the core's [`crate::Error`], wrapped unchanged in
//! [`RenderError::Input`].

/// Errors of the render layer (`render`): the GPU side, independent of files and inputs.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// wgpu finds no adapter (neither a GPU nor a software adapter such as lavapipe).
    #[error("no adapter found (install a GPU driver or Mesa's lavapipe, Debian package mesa-vulkan-drivers): {0}")]
    NoAdapter(String),
    /// The adapter `adapter` refuses to create a device or a pipeline (`what`).
    #[error("cannot create {what} on {adapter}: {message}")]
    Create {
        /// What could not be created (device, pipeline).
        what: &'static str,
        /// The adapter's name.
        adapter: String,
        /// What wgpu said.
        message: String,
    },
    /// A wgpu validation error while drawing a frame.
    #[error("GPU validation error: {0}")]
    Validation(String),
    /// GPU culling was forced ([`crate::render::headless::Culling::Gpu`]) but cannot run.
    #[error("GPU culling forced but {0}")]
    GpuCullingUnavailable(String),
    /// Waiting for the GPU or reading a buffer back failed (`stage`: poll, map, range).
    #[error("readback ({stage}) failed: {message}")]
    Readback {
        /// Which step of the readback.
        stage: &'static str,
        /// What wgpu said.
        message: String,
    },
    /// An internal ordering invariant of the renderer was broken (a bug): `what` was missing.
    #[error("internal: {0} missing")]
    Internal(&'static str),
    /// An invalid argument or mesh: the core's error, message unchanged.
    #[error(transparent)]
    Input(#[from] crate::Error),
}

/// Result alias of the render layer.
pub type Result<T> = std::result::Result<T, RenderError>;

