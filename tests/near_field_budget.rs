//! The near field's full-detail trees are bounded by their leaf cards, not only by their count
//! (`sylva::job::adapted::choose_full_detail`, trial 39).

use sylva::job::adapted::{cache, choose_full_detail, full_detail_cost, DEFAULT_MAX_FULL_CARDS, DEFAULT_MAX_FULL_TREES};
use sylva::species::SpeciesLibrary;
use sylva::structure::stand::{age_class, crown_base_class};

/// The rule: the largest on screen first, each while it fits in what is left; a tree that does
/// not fit is passed over and a cheaper one after it may still fit; never more than the count.
#[test]
fn full_detail_is_chosen_within_the_card_budget_and_the_count() {
    assert_eq!(choose_full_detail(&[5, 5, 3, 1], 3, 9), [true, false, true, true]);
    assert_eq!(choose_full_detail(&[5, 5, 3, 1], 2, 9), [true, false, true, false]);
    assert_eq!(choose_full_detail(&[5, 5, 3, 1], 10, 100), [true; 4]);
    assert_eq!(choose_full_detail(&[], 10, 100), Vec::<bool>::new());
}

/// Trial 39: the close-up of a dense 65-year Norway spruce planting (2.5 m spacing) took
/// 10.1 GiB: its 200 full-detail trees held 25.9 M leaf cards (`--stats`), where the default
/// run's beeches hold 1.3 M. The budget keeps 200 full-detail beeches at full age (as before)
/// and cuts the spruces to those whose open-grown cards fit: fewer than 40 of 200.
#[test]
fn a_dense_spruce_close_up_is_cut_to_the_card_budget_and_beeches_are_not() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let mut c = cache(7).full;
    let spruce = (lib.find("norway_spruce").unwrap(), age_class(65.0), crown_base_class(20.0, 8.0));
    let beech = (lib.find("beech").unwrap(), age_class(100.0), crown_base_class(25.0, 12.0));
    c.prepare(&lib, &[spruce, beech]).unwrap();
    let (cs, cb) = (full_detail_cost(&c, spruce), full_detail_cost(&c, beech));
    eprintln!("full-detail cost (leaf cards + nodes): spruce of 65 years {cs}, beech of 100 years {cb}");
    assert!(cb > 0 && cs > 5 * cb, "spruce {cs}, beech {cb}");
    let n = DEFAULT_MAX_FULL_TREES;
    let beeches = choose_full_detail(&vec![cb; n], n, DEFAULT_MAX_FULL_CARDS);
    assert!(beeches.iter().all(|&b| b), "{} of {n} beeches at full detail", beeches.iter().filter(|&&b| b).count());
    let spruces = choose_full_detail(&vec![cs; n], n, DEFAULT_MAX_FULL_CARDS);
    let k = spruces.iter().filter(|&&b| b).count();
    assert_eq!(k, DEFAULT_MAX_FULL_CARDS / cs, "spruces at full detail");
    assert!(k >= 1 && k < 40 && k * cs <= DEFAULT_MAX_FULL_CARDS, "{k} spruces of {cs}");
    // the first k are the ones taken (the largest on screen)
    assert!(spruces[..k].iter().all(|&b| b) && spruces[k..].iter().all(|&b| !b));
}
