// The world's cell words (docs/FORMAT.md §5.1–5.3): the top two bits say empty, full or
// mixed; a full cell's low 15 bits are its material, a mixed one's low 30 bits point at its
// children (64 blocks, or a block's voxel group).

/** Where a cell's state starts. */
export const STATE_SHIFT = 30;
/** The states. */
export const EMPTY = 0;
export const FULL = 1;
export const MIXED = 2;
/** A full cell's (and a solid voxel's) material bits. */
export const MATERIAL_MASK = 0x7fff;
/** A mixed cell's pointer bits. */
export const POINTER_MASK = 0x3fffffff;
/** Blocks per chunk; words per mixed block's voxel group (two 16-bit voxels a word). */
export const BLOCKS = 64;
export const GROUP_WORDS = 32;

/** The state of a cell word. */
export const state = (cell: number) => cell >>> STATE_SHIFT;
