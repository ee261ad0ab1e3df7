//! Composing labelled image grids (for `compare`), with a tiny built-in 5x7 font so the
//! labels need no font file or dependency.

use obscura::RgbImage;

/// A 5x7 glyph: seven rows of five columns, `#` set.
fn glyph(c: char) -> [&'static str; 7] {
    match c.to_ascii_lowercase() {
        'a' => [
            ".....", ".....", ".###.", "....#", ".####", "#...#", ".####",
        ],
        'b' => [
            "#....", "#....", "####.", "#...#", "#...#", "#...#", "####.",
        ],
        'c' => [
            ".....", ".....", ".###.", "#....", "#....", "#....", ".###.",
        ],
        'd' => [
            "....#", "....#", ".####", "#...#", "#...#", "#...#", ".####",
        ],
        'e' => [
            ".....", ".....", ".###.", "#...#", "#####", "#....", ".###.",
        ],
        'f' => [
            "..##.", ".#...", "####.", ".#...", ".#...", ".#...", ".#...",
        ],
        'g' => [
            ".....", ".####", "#...#", "#...#", ".####", "....#", ".###.",
        ],
        'h' => [
            "#....", "#....", "####.", "#...#", "#...#", "#...#", "#...#",
        ],
        'i' => [
            "..#..", ".....", ".##..", "..#..", "..#..", "..#..", ".###.",
        ],
        'j' => [
            "...#.", ".....", "..##.", "...#.", "...#.", "#..#.", ".##..",
        ],
        'k' => [
            "#....", "#....", "#..#.", "#.#..", "##...", "#.#..", "#..#.",
        ],
        'l' => [
            ".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###.",
        ],
        'm' => [
            ".....", ".....", "##.#.", "#.#.#", "#.#.#", "#.#.#", "#.#.#",
        ],
        'n' => [
            ".....", ".....", "####.", "#...#", "#...#", "#...#", "#...#",
        ],
        'o' => [
            ".....", ".....", ".###.", "#...#", "#...#", "#...#", ".###.",
        ],
        'p' => [
            ".....", "####.", "#...#", "#...#", "####.", "#....", "#....",
        ],
        'q' => [
            ".....", ".####", "#...#", "#...#", ".####", "....#", "....#",
        ],
        'r' => [
            ".....", ".....", "#.##.", "##..#", "#....", "#....", "#....",
        ],
        's' => [
            ".....", ".....", ".####", "#....", ".###.", "....#", "####.",
        ],
        't' => [
            ".#...", ".#...", "####.", ".#...", ".#...", ".#..#", "..##.",
        ],
        'u' => [
            ".....", ".....", "#...#", "#...#", "#...#", "#..##", ".##.#",
        ],
        'v' => [
            ".....", ".....", "#...#", "#...#", "#...#", ".#.#.", "..#..",
        ],
        'w' => [
            ".....", ".....", "#...#", "#.#.#", "#.#.#", "#.#.#", ".#.#.",
        ],
        'x' => [
            ".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#",
        ],
        'y' => [
            ".....", "#...#", "#...#", "#...#", ".####", "....#", ".###.",
        ],
        'z' => [
            ".....", ".....", "#####", "...#.", "..#..", ".#...", "#####",
        ],
        '0' => [
            ".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###.",
        ],
        '1' => [
            "..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###.",
        ],
        '2' => [
            ".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####",
        ],
        '3' => [
            "#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###.",
        ],
        '4' => [
            "...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#.",
        ],
        '5' => [
            "#####", "#....", "####.", "....#", "....#", "#...#", ".###.",
        ],
        '6' => [
            "..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###.",
        ],
        '7' => [
            "#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#...",
        ],
        '8' => [
            ".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###.",
        ],
        '9' => [
            ".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##..",
        ],
        '-' => [
            ".....", ".....", ".....", "#####", ".....", ".....", ".....",
        ],
        '.' => [
            ".....", ".....", ".....", ".....", ".....", ".##..", ".##..",
        ],
        ':' => [
            ".....", ".##..", ".##..", ".....", ".##..", ".##..", ".....",
        ],
        '%' => [
            "##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##",
        ],
        '/' => [
            ".....", "....#", "...#.", "..#..", ".#...", "#....", ".....",
        ],
        '(' => [
            "..#..", ".#...", "#....", "#....", "#....", ".#...", "..#..",
        ],
        ')' => [
            "..#..", "...#.", "....#", "....#", "....#", "...#.", "..#..",
        ],
        ',' => [
            ".....", ".....", ".....", ".....", ".##..", "..#..", ".#...",
        ],
        _ => [
            ".....", ".....", ".....", ".....", ".....", ".....", ".....",
        ],
    }
}

/// Draws `text` with its top-left corner at `(x, y)`, `scale` pixels per font pixel,
/// clipped to the image.
pub fn draw_text(img: &mut RgbImage, x: i64, y: i64, text: &str, scale: i64, color: [u8; 3]) {
    for (k, c) in text.chars().enumerate() {
        let g = glyph(c);
        let ox = x + k as i64 * 6 * scale;
        for (row, bits) in g.iter().enumerate() {
            for (col, b) in bits.bytes().enumerate() {
                if b != b'#' {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let (px, py) = (ox + col as i64 * scale + dx, y + row as i64 * scale + dy);
                        if px >= 0 && py >= 0 && (px as u32) < img.width && (py as u32) < img.height
                        {
                            img.pixels[py as usize * img.width as usize + px as usize] = color;
                        }
                    }
                }
            }
        }
    }
}

/// Height in pixels of a label band for text at `scale`.
pub fn label_height(scale: i64) -> u32 {
    (7 * scale + 6) as u32
}

/// Lays out tiles (all the same size) `columns` per row, each with a label band above
/// it, separated by a margin.
pub fn compose(tiles: &[(String, RgbImage)], columns: usize) -> RgbImage {
    let Some((_, first)) = tiles.first() else {
        return RgbImage::new(1, 1);
    };
    let (tw, th) = (first.width, first.height);
    let scale = if tw >= 480 { 2 } else { 1 };
    let (margin, band) = (4u32, label_height(scale));
    let columns = columns.max(1);
    let rows = tiles.len().div_ceil(columns);
    let width = columns as u32 * (tw + margin) + margin;
    let height = rows as u32 * (th + band + margin) + margin;
    let mut out = RgbImage::new(width, height);
    out.pixels.iter_mut().for_each(|p| *p = [40, 40, 44]);
    for (k, (label, tile)) in tiles.iter().enumerate() {
        let (col, row) = ((k % columns) as u32, (k / columns) as u32);
        let x0 = margin + col * (tw + margin);
        let y0 = margin + row * (th + band + margin);
        draw_text(
            &mut out,
            i64::from(x0) + 2,
            i64::from(y0) + 3,
            label,
            scale,
            [235, 235, 235],
        );
        for y in 0..th.min(tile.height) {
            for x in 0..tw.min(tile.width) {
                out.pixels[(y0 + band + y) as usize * width as usize + (x0 + x) as usize] =
                    tile.pixels[y as usize * tile.width as usize + x as usize];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_are_five_by_seven() {
        for c in "abcdefghijklmnopqrstuvwxyz0123456789-.:%/(), ".chars() {
            assert!(glyph(c).iter().all(|r| r.len() == 5), "{c}");
        }
    }

    #[test]
    fn compose_places_tiles_and_labels() {
        let mut a = RgbImage::new(10, 8);
        a.pixels.iter_mut().for_each(|p| *p = [255, 0, 0]);
        let out = compose(
            &[
                ("a".into(), a.clone()),
                ("b".into(), a.clone()),
                ("c".into(), a),
            ],
            2,
        );
        assert_eq!(out.width, 2 * 14 + 4);
        assert_eq!(out.height, 2 * (8 + label_height(1) + 4) + 4);
        // the first tile's top-left pixel is red, below its label band
        let y = 4 + label_height(1);
        assert_eq!(out.pixels[y as usize * out.width as usize + 4], [255, 0, 0]);
        // the label drew something light in the band
        assert!(
            out.pixels[..(y as usize * out.width as usize)]
                .iter()
                .any(|p| p[0] > 200 && p[1] > 200)
        );
    }
}
