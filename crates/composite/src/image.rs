//! Premultiplied RGBA images and pieces of them, and the over operator.

/// A premultiplied linear RGBA f32 image, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` pixels.
    pub pixels: Vec<[f32; 4]>,
}

impl Layer {
    /// A transparent image.
    pub fn transparent(width: u32, height: u32) -> Self {
        Self { width, height, pixels: vec![[0.0; 4]; width as usize * height as usize] }
    }

    /// The number of pixels.
    pub fn len(&self) -> usize {
        self.pixels.len()
    }

    /// True for an image of no pixels.
    pub fn is_empty(&self) -> bool {
        self.pixels.is_empty()
    }
}

/// A range of pixel indices `[start, end)` of a row-major image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelRange {
    /// First pixel.
    pub start: usize,
    /// One past the last pixel.
    pub end: usize,
}

impl PixelRange {
    /// Part `i` of `parts` equal parts of this range (the first ones one pixel shorter when it
    /// does not divide).
    pub fn part(&self, i: usize, parts: usize) -> PixelRange {
        let n = self.end - self.start;
        PixelRange { start: self.start + n * i / parts, end: self.start + n * (i + 1) / parts }
    }

    /// Its length.
    pub fn len(&self) -> usize {
        self.end - self.start
    }

    /// True for an empty range.
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }
}

/// `front` over `back`, premultiplied: `front + (1 − α_front)·back`.
#[inline]
pub fn over_front_to_back(front: [f32; 4], back: [f32; 4]) -> [f32; 4] {
    let t = 1.0 - front[3];
    [front[0] + t * back[0], front[1] + t * back[1], front[2] + t * back[2], front[3] + t * back[3]]
}
