//! Built-in examples.

use lamdyn_material::laminate::SandwichStack;
use lamdyn_material::law::PaperEq7Law;

/// The paper's roof: Table 1 stack (glass E = 70 GPa as in eq. 35) and the Table 2 eq. 7 law.
pub fn paper_roof() -> (SandwichStack, PaperEq7Law) {
    (SandwichStack::paper_roof(), PaperEq7Law::paper_table2())
}
